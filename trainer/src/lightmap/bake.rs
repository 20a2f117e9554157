//! Baking a clip into SH light maps: every frame's texels (each the surface point and
//! interpolated normal the atlas gives it, on that frame's posed mesh) baked by the vertex
//! bake's own code ([`crate::bake::bake_points`]), through a checkpoint like `aprt train`'s,
//! which a bake farm's shards may share ([`bake_light_map_shard`]).

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};

use super::codec::{MapSequence, atlas_record};
use super::layout::{AtlasSpec, layout_for, texture_of_file};
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
    /// Its UV layout (also in `sequence.layout` when generated).
    pub layout: UvLayout,
    /// Wall-clock seconds of the bake (resumed frames cost nothing).
    pub seconds: f64,
}

/// Refuses a sequence file (`bytes`, called `name`) baked on other UVs than `rig`'s: its maps
/// would be sampled at the wrong texels without any other sign. A file that stores its own
/// light-map UVs must have as many triangles as the character. A file older than the
/// fingerprint (version 1 or 2) is read unchecked, with a note to `reporter` saying so.
pub fn check_atlas(name: &str, bytes: &[u8], rig: &dyn Rig, reporter: &dyn Reporter) -> Result<()> {
    let (recorded, stored_triangles) =
        atlas_record(bytes).with_context(|| format!("{name}: invalid sequence"))?;
    let triangles = rig.bind_mesh().triangles.len();
    if stored_triangles > 0 {
        if stored_triangles != triangles {
            bail!(
                "{name} stores light-map UVs for {stored_triangles} triangles, the character has {triangles}: give the character the light map was baked from"
            );
        }
        return Ok(());
    }
    let Some(recorded) = recorded else {
        reporter.note(&format!(
            "note: {name} is a .shlm older than version 3 and records no atlas fingerprint: whether it was baked on this character's UVs is not checked"
        ));
        return Ok(());
    };
    let ours = texture_of_file(rig, name)?.fingerprint();
    if recorded != ours {
        bail!(
            "{name} was baked on UVs of atlas fingerprint {recorded:08x}, the character's UVs are {ours:08x}: give the character the light map was baked from"
        );
    }
    Ok(())
}

/// Bakes every frame of `clip` of `rig` at the texels of the atlas `spec` names (its
/// resolution and UVs), through the checkpoint `checkpoint` (removed once every frame is
/// baked). Overlapping texels (mirrored or overlapping UVs take the mean) are reported to
/// `reporter`.
pub fn bake_light_maps(
    rig: &dyn Rig,
    what: &str,
    clip: &Clip,
    spec: AtlasSpec,
    settings: &BakeSettings,
    checkpoint: &CheckpointSettings<'_>,
    reporter: &dyn Reporter,
) -> Result<BakedMaps> {
    let baking = atlas_and_meshes(rig, what, clip, (spec, settings), reporter)?;
    let target = Texels::new(&baking.atlas, &baking.layout);
    let mut store = Checkpoint::open_at(
        checkpoint.dir,
        checkpoint.existing,
        settings,
        &baking.meshes,
        &target,
    )?;
    let start = Instant::now();
    let values = store.bake_at(&baking.meshes, &target, frame_name(clip), reporter)?;
    let seconds = start.elapsed().as_secs_f64();
    let n2 = settings.order * settings.order;
    let Baking {
        layout,
        stored,
        atlas,
        ..
    } = baking;
    let frames = values.iter().map(|v| atlas.gather(v, n2)).collect();
    let sequence = MapSequence {
        resolution: spec.resolution,
        atlas: Some(layout.fingerprint()),
        order: settings.order,
        filled: atlas.filled(),
        positions: texel_positions(&atlas, rig.bind_mesh()),
        layout: stored.then(|| layout.clone()),
        frames,
    };
    store.remove()?;
    Ok(BakedMaps {
        sequence,
        atlas,
        layout,
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
    spec: AtlasSpec,
    settings: &BakeSettings,
    (dir, shard): (&Path, Shard),
    reporter: &dyn Reporter,
) -> Result<ShardBaked> {
    let baking = atlas_and_meshes(rig, what, clip, (spec, settings), reporter)?;
    let target = Texels::new(&baking.atlas, &baking.layout);
    let mut store =
        Checkpoint::open_at(dir, OnExisting::Resume, settings, &baking.meshes, &target)?;
    Ok(store.bake_shard(&baking.meshes, &target, shard, frame_name(clip), reporter)?)
}

/// What a light-map bake works on.
struct Baking {
    /// The UV layout, and whether the sequence stores it (generated UVs).
    layout: UvLayout,
    stored: bool,
    /// The layout rasterised.
    atlas: Atlas,
    /// The clip's posed meshes.
    meshes: Vec<Mesh>,
}

/// What a light-map bake of `clip` works on: the UV layout `spec` names, its atlas
/// (overlapping texels reported to `reporter`), and the posed meshes. The bake is estimated
/// against the run's budget ([`crate::bake::budget`]) as `train` and `simulate` are: first
/// with every texel of the atlas filled, before the atlas itself is rasterised (an 8192² atlas
/// alone is gigabytes), then with the samples it really has, before any frame is posed.
fn atlas_and_meshes(
    rig: &dyn Rig,
    what: &str,
    clip: &Clip,
    (spec, settings): (AtlasSpec, &BakeSettings),
    reporter: &dyn Reporter,
) -> Result<Baking> {
    let resolution = spec.resolution;
    // The baked values, the maps gathered from them and the encoder's copy.
    let copies = 3;
    let frames = clip.frames.len();
    let work = |texels| Workload::light_maps(frames, rig.bind_mesh(), texels, settings, copies);
    let estimate = format!("clip {} at --resolution {resolution}", clip.name);
    work(resolution.saturating_mul(resolution))
        .check(&format!("{estimate} (every texel filled)"))?;
    let (layout, stored) = layout_for(rig, what, spec.uvs, resolution)?;
    let atlas = Atlas::build(&layout, &rig.bind_mesh().triangles, resolution)
        .with_context(|| format!("{what}: building the {resolution}x{resolution} UV atlas"))?;
    work(atlas.samples().len()).check(&estimate)?;
    let overlapping = atlas.overlapping_texels();
    if overlapping > 0 {
        reporter.note(&format!(
            "note: {what}: {overlapping} texels lie on two or more triangles (mirrored or overlapping UVs); they hold the mean of those surface points' transfer"
        ));
    }
    let meshes = pose_all(rig, &clip.name, &clip.frames)?;
    Ok(Baking {
        layout,
        stored,
        atlas,
        meshes,
    })
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
