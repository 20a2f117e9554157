//! A frame's proxies: the spheres moved by the bones' skinning matrices, and for each bone
//! the mask of the proxies that can touch its vertices. Caller-owned and fixed-size, like the
//! pose and lighting weights.

use super::MAX_PROXIES;
use super::caps::Sphere;
use super::occlusion::{Block, Output, block_occlusion};
use super::section::{
    BONE_RECORD, PRELUDE, PROXY_RECORD, ProxyCheck, bone_record, prelude, proxy_record,
};
use crate::blob::format::{MAX_BONES, VERTEX_BLOCK};
use crate::blob::{Error, Input, ModelInfo, Reader, Resident};
use crate::eval::{Stamp, check_stamp, first_non_finite};
use crate::math;
use crate::rotation::Rotation;
use crate::sh::{MAX_COEFFS, MAX_ORDER, coeff_count};

/// A bone's skinning matrix, bind pose to posed, as an engine computes it for linear blend
/// skinning: 3 × 4, row-major, `[r00, r01, r02, t0, r10, r11, r12, t1, r20, r21, r22, t2]`.
pub type Skinning = [f32; 12];

/// The proxies of one frame, posed by [`Model::pose_proxies`](crate::Model::pose_proxies)
/// and read by [`Model::occlude`](crate::Model::occlude) and
/// [`Model::occlude_transfer`](crate::Model::occlude_transfer). About 4 KiB; `new` is a
/// `const fn`, so it can live in a `static`.
#[derive(Clone, Debug)]
pub struct ProxyFrame {
    pub(crate) stamp: Stamp,
    pub(crate) cull: f32,
    pub(crate) radii: [f32; MAX_PROXIES],
    /// The posed centres' coordinates and the reaches `r / √cull` (beyond which a cap is
    /// culled; infinite when nothing is), one array each, eight proxies a group: what a block
    /// tests eight proxies at a time against.
    pub(crate) groups: [[[f32; 8]; MAX_PROXIES / 8]; 4],
    /// Per bone, the proxies that may occlude its vertices this frame.
    pub(crate) candidates: [u64; MAX_BONES],
}

impl ProxyFrame {
    /// Empty: no model's proxies yet.
    pub const fn new() -> Self {
        Self {
            stamp: None,
            cull: 0.0,
            radii: [0.0; MAX_PROXIES],
            groups: [[[0.0; 8]; MAX_PROXIES / 8]; 4],
            candidates: [0; MAX_BONES],
        }
    }

    /// How many proxies may occlude the vertices of `bone` this frame: the contacts the
    /// per-vertex cost grows with.
    pub fn candidates(&self, bone: usize) -> u32 {
        self.candidates.get(bone).map_or(0, |m| m.count_ones())
    }

    /// Sets proxy `i`: posed centre, radius and reach (`r / √cull`, infinite when nothing is
    /// culled).
    pub(crate) fn set_sphere(&mut self, i: usize, centre: [f32; 3], radius: f32, reach: f32) {
        self.radii[i] = radius;
        let (g, k) = (i / 8, i % 8);
        for (axis, x) in centre.iter().enumerate() {
            self.groups[axis][g][k] = *x;
        }
        self.groups[3][g][k] = reach;
    }

    /// Proxy `i`: its centre, radius and reach.
    #[inline(always)]
    pub(crate) fn sphere(&self, i: usize) -> Sphere {
        let ([x, y, z, reach], (g, k)) = (&self.groups, (i / 8, i % 8));
        Sphere {
            centre: [x[g][k], y[g][k], z[g][k]],
            radius: self.radii[i],
            reach: reach[g][k],
        }
    }
}

impl Default for ProxyFrame {
    fn default() -> Self {
        Self::new()
    }
}

/// `M p` for a 3 × 4 row-major matrix.
fn apply(m: &Skinning, p: [f32; 3]) -> [f32; 3] {
    [0, 4, 8].map(|r| m[r] * p[0] + m[r + 1] * p[1] + m[r + 2] * p[2] + m[r + 3])
}

/// The largest column length of the matrix's linear part: how much it can grow a radius.
fn stretch(m: &Skinning) -> f32 {
    (0..3)
        .map(|c| math::sqrt(m[c] * m[c] + m[4 + c] * m[4 + c] + m[8 + c] * m[8 + c]))
        .fold(0.0, f32::max)
}

/// A proxies section on its own, validated: what a tool that writes one (the trainer) poses
/// and evaluates with exactly the code a model runs.
#[derive(Clone, Copy, Debug)]
pub struct ProxySet<'a> {
    bytes: &'a [u8],
    bones: usize,
}

impl<'a> ProxySet<'a> {
    /// The section's bytes (see FORMAT.md) for a model of `bones` bones, validated.
    pub fn parse(bytes: &'a [u8], bones: usize) -> Result<ProxySet<'a>, Error> {
        let mut check = ProxyCheck::new(bones);
        check.feed(bytes);
        check.finish()?;
        Ok(ProxySet { bytes, bones })
    }

    /// Poses the proxies by each bone's skinning matrix into `frame`, stamped with the
    /// section's CRC: a model's calls refuse it, [`ProxyFrame::occlusion`] takes it.
    pub fn pose(&self, skinning: &[Skinning], frame: &mut ProxyFrame) -> Result<(), Error> {
        let span = (0, self.bones);
        pose_section(&mut Resident(self.bytes), span, skinning, frame)?;
        frame.stamp = Some(crate::blob::format::crc32(self.bytes));
        Ok(())
    }
}

impl ProxyFrame {
    /// The occlusion `D` of one vertex of bone `bone` at `position` with `normal` (the posed
    /// mesh's, world space) into `out` (`order²` values, world frame, or the bone's frame
    /// when `rotation` is its rotation); `false` when no proxy reaches it (`out` is zeroed).
    /// The transfer with the proxies is the model's (or the skinned bind transfer's) minus
    /// `D`.
    pub fn occlusion(
        &self,
        order: usize,
        bone: usize,
        (position, normal): ([f32; 3], [f32; 3]),
        rotation: Option<&Rotation>,
        out: &mut [f32],
    ) -> Result<bool, Error> {
        if self.stamp.is_none() {
            return Err(Error::WeightsNotSet);
        }
        let n2 = coeff_count(order);
        if !(1..=MAX_ORDER).contains(&order) || out.len() < n2 {
            return Err(Error::WrongLength {
                what: Input::Transfer,
                expected: n2,
                found: out.len(),
            });
        }
        if first_non_finite(&position).is_some() {
            return Err(Error::NonFinitePosition { index: 0 });
        }
        let mut masks = [0; VERTEX_BLOCK];
        masks[0] = self.candidates.get(bone).copied().unwrap_or(0);
        let (mut positions, mut normals) =
            ([[0.0f32; 3]; VERTEX_BLOCK], [[0.0f32; 3]; VERTEX_BLOCK]);
        (positions[0], normals[0]) = (position, normal);
        let block = Block {
            masks,
            positions: &positions,
            normals: &normals,
            rotations: rotation.map(|r| [r; VERTEX_BLOCK]),
        };
        let mut lanes = [[0.0f32; MAX_COEFFS]; VERTEX_BLOCK];
        let reached = block_occlusion(self, order, &block, Output::Transfer(&mut lanes)) & 1 != 0;
        let out = &mut out[..n2];
        match reached {
            true => out.copy_from_slice(&lanes[0][..n2]),
            false => out.fill(0.0),
        }
        Ok(reached)
    }
}

impl ModelInfo {
    /// Whether the model has occluder proxies.
    pub fn has_proxies(&self) -> bool {
        self.proxies.is_some()
    }

    pub(crate) fn pose_proxies<R: Reader>(
        &self,
        r: &mut R,
        skinning: &[Skinning],
        frame: &mut ProxyFrame,
    ) -> Result<(), Error> {
        frame.stamp = None;
        let span = self.proxies.ok_or(Error::NoProxies)?;
        pose_section(r, (span.offset, self.bones()), skinning, frame)?;
        frame.stamp = Some(self.id);
        Ok(())
    }

    /// Checks that `frame` holds this model's posed proxies.
    pub(crate) fn check_proxy_frame(&self, frame: &ProxyFrame) -> Result<(), Error> {
        check_stamp(frame.stamp, self)
    }
}

/// Poses the proxies section at `offset` of a model of `bones` bones into `frame` (its stamp
/// is the caller's to set).
fn pose_section<R: Reader>(
    r: &mut R,
    (offset, bones): (u64, usize),
    skinning: &[Skinning],
    frame: &mut ProxyFrame,
) -> Result<(), Error> {
    frame.stamp = None;
    if skinning.len() != bones {
        return Err(Error::WrongLength {
            what: Input::Skinning,
            expected: bones,
            found: skinning.len(),
        });
    }
    if let Some(bone) = skinning
        .iter()
        .position(|m| m.iter().any(|x| !x.is_finite()))
    {
        return Err(Error::BadSkinning { bone });
    }
    let mut head = [0u8; PRELUDE];
    r.read_at(offset, &mut head)?;
    let (count, _, cull, _) = prelude(&head);
    // Validated at open; checked again, since a streamed source may have changed since.
    let count = (count as usize).min(MAX_PROXIES);
    let records = offset + PRELUDE as u64;
    // A proxy reaches no farther than where its cap shrinks to `cull`: `d = r / √cull`.
    let reach = |radius: f32| match cull > 0.0 {
        true => radius / math::sqrt(cull),
        false => f32::INFINITY,
    };
    r.chunks(records, PROXY_RECORD, count, |first, bytes| {
        for (i, record) in bytes.chunks_exact(PROXY_RECORD).enumerate() {
            let (bone, centre, radius) = proxy_record(record);
            let m = skinning.get(bone as usize).ok_or(Error::BadProxies)?;
            let radius = radius * stretch(m);
            frame.set_sphere(first + i, apply(m, centre), radius, reach(radius));
        }
        Ok(())
    })?;
    frame.cull = cull;
    frame.candidates = [0; MAX_BONES];
    let bone_records = records + (count * PROXY_RECORD) as u64;
    r.chunks(bone_records, BONE_RECORD, bones, |first, bytes| {
        for (i, record) in bytes.chunks_exact(BONE_RECORD).enumerate() {
            let b = first + i;
            let (centre, radius, ignored) = bone_record(record);
            let m = skinning.get(b).ok_or(Error::BadProxies)?;
            let (centre, radius) = (apply(m, centre), radius * stretch(m));
            // The bone's bound meets the proxy's reach: `|c − c_p| ≤ r + reach_p`, squared.
            let mut mask = 0u64;
            for p in 0..count {
                let proxy = frame.sphere(p);
                let v = [0, 1, 2].map(|k| centre[k] - proxy.centre[k]);
                let gap = radius + proxy.reach;
                let meets = v[0] * v[0] + v[1] * v[1] + v[2] * v[2] <= gap * gap;
                if ignored >> p & 1 == 0 && meets {
                    mask |= 1 << p;
                }
            }
            *frame.candidates.get_mut(b).ok_or(Error::BadProxies)? = mask;
        }
        Ok(())
    })
}
