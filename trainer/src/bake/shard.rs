//! Bake farms: `--shard I/N` bakes one machine's share of a clip's frames into a checkpoint
//! shared by (or later merged with) the other shards, and a final `--resume` fits the model.
//!
//! Shard `I` of `N` takes the frames `f` with `f % N == I`. Interleaving rather than
//! contiguous ranges gives every shard the same work even when the cost of a pose varies along
//! the clip (a crouch that folds the mesh onto itself casts more occluded rays than a stand).
//! Which frames a shard takes is the only thing sharding decides: each frame is baked exactly
//! as a single run bakes it, so the merged checkpoint holds the same bits (see
//! `docs/guide/bake-farms.md`).

use std::fmt;
use std::str::FromStr;

/// One machine's share of a bake: shard `index` of `count`, 0-based.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    index: usize,
    count: usize,
}

/// Why a shard spec (`--shard I/N`) is refused. The messages leave out the spec, which the
/// command line's error already quotes.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ShardError {
    /// Not two whole numbers separated by `/`.
    #[error("expected INDEX/COUNT, two whole numbers such as 0/4 (shards are numbered from 0)")]
    Syntax,
    /// No shards at all.
    #[error("the count must be at least 1")]
    NoShards,
    /// The index names a shard that does not exist.
    #[error("the index must be below the count (0-based: shards 0/{count} to {last}/{count})", last = count - 1)]
    Index {
        /// The shard count.
        count: usize,
    },
}

impl Shard {
    /// Shard `index` of `count`, 0-based.
    pub fn new(index: usize, count: usize) -> Result<Shard, ShardError> {
        if count == 0 {
            return Err(ShardError::NoShards);
        }
        if index >= count {
            return Err(ShardError::Index { count });
        }
        Ok(Shard { index, count })
    }

    /// The shard's number, from 0.
    pub fn index(self) -> usize {
        self.index
    }

    /// How many shards share the bake.
    pub fn count(self) -> usize {
        self.count
    }

    /// Whether frame `frame` (its index in the checkpoint) is this shard's to bake.
    pub fn holds(self, frame: usize) -> bool {
        frame % self.count == self.index
    }

    /// How many of `frames` frames are this shard's.
    pub fn share(self, frames: usize) -> usize {
        frames.saturating_sub(self.index).div_ceil(self.count)
    }
}

impl FromStr for Shard {
    type Err = ShardError;

    /// `I/N`, as `--shard` takes it.
    fn from_str(spec: &str) -> Result<Shard, ShardError> {
        let number = |s: &str| {
            let digits = !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
            digits.then(|| s.parse::<usize>().ok()).flatten()
        };
        let (index, count) = spec
            .split_once('/')
            .and_then(|(i, n)| Some((number(i)?, number(n)?)))
            .ok_or(ShardError::Syntax)?;
        Shard::new(index, count)
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_parse_and_bad_ones_say_why() {
        let s: Shard = "1/3".parse().unwrap();
        assert_eq!((s.index(), s.count(), s.to_string()), (1, 3, "1/3".into()));
        assert_eq!("0/1".parse::<Shard>().unwrap(), Shard::new(0, 1).unwrap());
        let message = |spec: &str| spec.parse::<Shard>().unwrap_err().to_string();
        assert_eq!(
            message("3/3"),
            "the index must be below the count (0-based: shards 0/3 to 2/3)"
        );
        assert_eq!(message("0/0"), "the count must be at least 1");
        for bad in [
            "", "1", "1/", "/3", "-1/3", "1/3/4", "a/3", "+1/3", "1.0/3", " 1/3",
        ] {
            assert!(message(bad).contains("expected INDEX/COUNT"), "{bad}");
        }
    }

    #[test]
    fn shards_interleave_and_cover_every_frame_once() {
        for count in 1..6 {
            for frames in 0..12 {
                let shards: Vec<Shard> =
                    (0..count).map(|i| Shard::new(i, count).unwrap()).collect();
                for f in 0..frames {
                    assert_eq!(shards.iter().filter(|s| s.holds(f)).count(), 1);
                }
                for s in &shards {
                    let held = (0..frames).filter(|&f| s.holds(f)).count();
                    assert_eq!(s.share(frames), held, "{s} of {frames}");
                }
            }
        }
    }
}
