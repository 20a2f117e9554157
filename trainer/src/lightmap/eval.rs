//! `aprt lightmap eval`: a sequence's or a light-map model's maps read at every vertex of every
//! frame of a clip, one frame's filled texels at a time. It never holds a frame's `R²` map,
//! let alone every frame's: a 38 KB model whose atlas claimed 8192² aborted on a failed 1 GiB
//! allocation, and a 1024² model evaluated at 240 fps peaked at 2.4 GB to write a 192 KB
//! .npy. What the output holds is estimated first and refused beyond the run's budget.

use anyhow::{Context, Result, bail};

use super::bake::check_atlas;
use super::codec::{MAGIC, ShlmFile};
use super::layout::stored_or_texture;
use super::model::{ModelFrames, model_layout};
use super::sample::rows_at_vertices;
use crate::bake::budget::Workload;
use crate::progress::Reporter;
use crate::rig::uv::UvLayout;
use crate::rig::{Clip, Rig};

/// Most bytes of a model's predicted rows held at once: the frames predicted per call into
/// the model (at least one). Each call parses the blob, so a frame at a time would cost a
/// large model's validation every frame.
const CHUNK_BYTES: usize = 64 << 20;

/// Copies of the output held at the peak: the values and the .npy's bytes.
const OUTPUT_COPIES: usize = 2;

/// Every frame of `clip` of `rig` read at the bind mesh's vertices (each vertex the bilinear
/// sample at its UVs, as [`super::sample::at_vertices`]) from `bytes`, a `.shlm` sequence or a
/// light-map model called `name`: `frames × vertices × n²` values and that shape. Refused,
/// naming `name` and the bytes, when the output would not fit the run's budget.
pub fn eval_at_vertices(
    name: &str,
    bytes: &[u8],
    rig: &dyn Rig,
    clip: &Clip,
    reporter: &dyn Reporter,
) -> Result<(Vec<f32>, [usize; 3])> {
    let frames = clip.frames.len();
    let bind = rig.bind_mesh();
    let shape = |order: usize| [frames, bind.vertex_count(), order * order];
    let check = |order: usize| {
        let [f, v, n2] = shape(order);
        Workload::evaluation(f, v, n2, OUTPUT_COPIES)
            .check(&format!("{name} on clip {}", clip.name))
    };
    let uvs_of = |layout: UvLayout| layout.vertex_uvs(&bind.triangles, bind.vertex_count());
    let mut out = Vec::new();
    if bytes.starts_with(MAGIC) {
        check_atlas(name, bytes, rig, reporter)?;
        let file = ShlmFile::parse(bytes).with_context(|| format!("{name}: invalid sequence"))?;
        if file.frames() != frames {
            bail!(
                "{name} holds {} frames, clip {} has {frames}: give the clip the sequence was baked from",
                file.frames(),
                clip.name
            );
        }
        let (r, order) = (file.resolution(), file.order());
        check(order)?;
        let uvs = uvs_of(stored_or_texture(file.layout(), rig, name)?);
        for k in 0..frames {
            let rows = file
                .decode_rows(k)
                .with_context(|| format!("{name}: decoding frame {k}"))?;
            out.extend(rows_at_vertices(
                &rows,
                file.texels(),
                r,
                order * order,
                &uvs,
            ));
        }
        return Ok((out, shape(order)));
    }
    let model = ModelFrames::new(bytes, name, rig, clip)?;
    let (r, order) = (model.resolution, model.order);
    check(order)?;
    let uvs = uvs_of(stored_or_texture(
        model_layout(bytes, name)?.as_ref(),
        rig,
        name,
    )?);
    let frame_bytes = (model.texels.len() * order * order * 4).max(1);
    let chunk = (CHUNK_BYTES / frame_bytes).max(1);
    for start in (0..frames).step_by(chunk) {
        for rows in model.predict(start..(start + chunk).min(frames))? {
            out.extend(rows_at_vertices(
                &rows,
                &model.texels,
                r,
                order * order,
                &uvs,
            ));
        }
    }
    Ok((out, shape(order)))
}
