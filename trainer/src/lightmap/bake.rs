//! Baking a clip into SH light maps: every frame's texels (each the surface point and
//! interpolated normal the atlas gives it, on that frame's posed mesh) baked by the vertex
//! bake's own code ([`crate::bake::bake_points`]), through a checkpoint like `aprt train`'s,
//! which a bake farm's shards may share ([`bake_light_map_shard`]).

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};

use super::codec::{MapSequence, atlas_fingerprint};
use crate::bake::budget::Workload;
use crate::bake::checkpoint::{BakeTarget, Checkpoint, OnExisting, ShardBaked};
use crate::bake::clip::pose_all;
use crate::bake::shard::Shard;
use crate::bake::{BakeError, BakeSettings, PatternRotation, bake_points};
use crate::progress::{BakeProgress, Reporter};
use crate::rig::mesh::Mesh;
use crate::rig::uv::{Atlas, UvLayout};
use crate::rig::{Clip, Rig};

/// The texels of an atlas, as the points a checkpoint bakes.
pub struct Texels<'a> {
    atlas: &'a Atlas,
    /// CRC-32 of the layout's UVs, so a resume with other UVs is refused.
    uv_crc: u32,
}

impl<'a> Texels<'a> {
    /// The texels of `atlas`, built from `layout`.
    pub fn new(atlas: &'a Atlas, layout: &UvLayout) -> Self {
        Texels {
            atlas,
            uv_crc: layout.fingerprint(),
        }
    }
}

impl BakeTarget for Texels<'_> {
    fn describe(&self) -> String {
        let r = self.atlas.resolution();
        format!(
            "texels of a {r}x{r} atlas ({} samples, UV CRC {:08x})",
            self.atlas.samples().len(),
            self.uv_crc
        )
    }

    fn points(&self, _mesh: &Mesh) -> usize {
        self.atlas.samples().len()
    }

    fn bake(
        &self,
        mesh: &Mesh,
        settings: &BakeSettings,
        progress: &dyn BakeProgress,
    ) -> Result<Vec<f32>, BakeError> {
        let (positions, normals) = self.atlas.surface(mesh);
        bake_points(
            mesh,
            (&positions, &normals),
            PatternRotation::Shared,
            settings,
            progress,
        )
    }
}

/// Where a light-map bake keeps its finished frames, and what it does with an existing one.
pub struct CheckpointSettings<'a> {
    /// The checkpoint directory.
    pub dir: &'a Path,
    /// Resume or refuse an existing checkpoint.
    pub existing: OnExisting,
}

/// A baked light-map sequence and what the bake measured.
pub struct BakedMaps {
    /// The maps, one per frame, with the filled texels and their bind positions.
    pub sequence: MapSequence,
    /// The atlas the maps were baked on.
    pub atlas: Atlas,
    /// Wall-clock seconds of the bake (resumed frames cost nothing).
    pub seconds: f64,
}

/// The rig's UV layout, or the error that says the character has none.
pub fn uv_layout<'r>(rig: &'r dyn Rig, what: &str) -> Result<&'r UvLayout> {
    match rig.uv_layout() {
        Some(layout) => Ok(layout),
        None => bail!(
            "{what} has no texture coordinates (glTF TEXCOORD_0, OBJ vt): an SH light map needs a UV atlas"
        ),
    }
}

/// Refuses a sequence file (`bytes`, called `name`) baked on other UVs than `rig`'s: its maps
/// would be sampled at the wrong texels without any other sign. A file older than the
/// fingerprint (version 1 or 2) is read unchecked, with a note to `reporter` saying so.
pub fn check_atlas(name: &str, bytes: &[u8], rig: &dyn Rig, reporter: &dyn Reporter) -> Result<()> {
    let recorded = atlas_fingerprint(bytes).with_context(|| format!("{name}: invalid sequence"))?;
    let Some(recorded) = recorded else {
        reporter.note(&format!(
            "note: {name} is a .shlm older than version 3 and records no atlas fingerprint: whether it was baked on this character's UVs is not checked"
        ));
        return Ok(());
    };
    let ours = uv_layout(rig, "the character")?.fingerprint();
    if recorded != ours {
        bail!(
            "{name} was baked on UVs of atlas fingerprint {recorded:08x}, the character's UVs are {ours:08x}: give the character the light map was baked from"
        );
    }
    Ok(())
}

/// Bakes every frame of `clip` of `rig` at the texels of an atlas of `resolution`² on the
/// rig's UV layout, through the checkpoint `checkpoint` (removed once every frame is baked).
/// Overlapping texels (mirrored or overlapping UVs take the mean) are reported to `reporter`.
pub fn bake_light_maps(
    rig: &dyn Rig,
    what: &str,
    clip: &Clip,
    resolution: usize,
    settings: &BakeSettings,
    checkpoint: &CheckpointSettings<'_>,
    reporter: &dyn Reporter,
) -> Result<BakedMaps> {
    let (layout, atlas, meshes) =
        atlas_and_meshes(rig, what, clip, (resolution, settings), reporter)?;
    let target = Texels::new(&atlas, layout);
    let mut store = Checkpoint::open_at(
        checkpoint.dir,
        checkpoint.existing,
        settings,
        &meshes,
        &target,
    )?;
    let start = Instant::now();
    let values = store.bake_at(&meshes, &target, frame_name(clip), reporter)?;
    let seconds = start.elapsed().as_secs_f64();
    let n2 = settings.order * settings.order;
    let frames = values.iter().map(|v| atlas.gather(v, n2)).collect();
    let sequence = MapSequence {
        resolution,
        atlas: Some(layout.fingerprint()),
        order: settings.order,
        filled: atlas.filled(),
        positions: texel_positions(&atlas, rig.bind_mesh()),
        frames,
    };
    store.remove()?;
    Ok(BakedMaps {
        sequence,
        atlas,
        seconds,
    })
}

/// Bakes `shard`'s share of the frames [`bake_light_maps`] bakes into the checkpoint directory
/// `dir` (the pair is the shard's place in the farm), started or joined (the shards share
/// it), and stops: a final [`bake_light_maps`] with [`OnExisting::Resume`] over the merged
/// checkpoint writes the sequence.
pub fn bake_light_map_shard(
    rig: &dyn Rig,
    what: &str,
    clip: &Clip,
    resolution: usize,
    settings: &BakeSettings,
    (dir, shard): (&Path, Shard),
    reporter: &dyn Reporter,
) -> Result<ShardBaked> {
    let (layout, atlas, meshes) =
        atlas_and_meshes(rig, what, clip, (resolution, settings), reporter)?;
    let target = Texels::new(&atlas, layout);
    let mut store = Checkpoint::open_at(dir, OnExisting::Resume, settings, &meshes, &target)?;
    Ok(store.bake_shard(&meshes, &target, shard, frame_name(clip), reporter)?)
}

/// What a light-map bake of `clip` works on: the rig's UV layout, its atlas of
/// `resolution`² texels (overlapping texels reported to `reporter`), and the posed meshes.
/// The bake is estimated against the run's budget ([`crate::bake::budget`]) as `train` and
/// `simulate` are: first with every texel of the atlas filled, before the atlas itself is
/// rasterised (an 8192² atlas alone is gigabytes), then with the samples it really has, before
/// any frame is posed.
fn atlas_and_meshes<'r>(
    rig: &'r dyn Rig,
    what: &str,
    clip: &Clip,
    (resolution, settings): (usize, &BakeSettings),
    reporter: &dyn Reporter,
) -> Result<(&'r UvLayout, Atlas, Vec<Mesh>)> {
    let layout = uv_layout(rig, what)?;
    // The baked values, the maps gathered from them and the encoder's copy.
    let copies = 3;
    let frames = clip.frames.len();
    let work = |texels| Workload::light_maps(frames, rig.bind_mesh(), texels, settings, copies);
    let estimate = format!("clip {} at --resolution {resolution}", clip.name);
    work(resolution.saturating_mul(resolution))
        .check(&format!("{estimate} (every texel filled)"))?;
    let atlas = Atlas::build(layout, &rig.bind_mesh().triangles, resolution)
        .with_context(|| format!("{what}: building the {resolution}x{resolution} UV atlas"))?;
    work(atlas.samples().len()).check(&estimate)?;
    let overlapping = atlas.overlapping_texels();
    if overlapping > 0 {
        reporter.note(&format!(
            "note: {what}: {overlapping} texels lie on two or more triangles (mirrored or overlapping UVs); they hold the mean of those surface points' transfer"
        ));
    }
    let meshes = pose_all(rig, &clip.name, &clip.frames)?;
    Ok((layout, atlas, meshes))
}

/// How frame `f` of `clip` is named in errors.
fn frame_name(clip: &Clip) -> impl Fn(usize) -> String + '_ {
    |f| format!("clip {} frame {f}", clip.name)
}

/// The bind-pose surface point of every filled texel, in texel order: where a runtime lights
/// the texel (the mean over its samples; gutter texels take their neighbours').
pub fn texel_positions(atlas: &Atlas, bind: &Mesh) -> Vec<[f32; 3]> {
    let (positions, _) = atlas.surface(bind);
    let flat: Vec<f32> = positions.into_iter().flatten().collect();
    let map = atlas.gather(&flat, 3);
    atlas
        .filled()
        .iter()
        .enumerate()
        .filter(|&(_, &f)| f)
        .map(|(t, _)| [map[3 * t], map[3 * t + 1], map[3 * t + 2]])
        .collect()
}
