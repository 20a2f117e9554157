//! Composing light maps under lights (`SHLM = Σ_i L_i · SHLM_i`, through aprt-core, each
//! texel lit at its bind-pose position, through the model's irradiance rig when it has one) and the preview `aprt lightmap compose` writes: the light
//! map, and with the character the frame rendered with it beside its per-vertex ray-traced
//! shading and their error, each panel titled and the error map's colour bar under them.

use std::path::Path;

use anyhow::{Context, Result, bail};
use aprt_core::{IrradianceRig, Light, Placement, Rgb};
use image::{Rgb as Pixel, RgbImage, imageops};

use crate::bake::{BakeSettings, bake_pose};
use crate::lighting::luminance;
use crate::lightmap::bake::texel_positions;
use crate::lightmap::codec::{MAGIC, ShlmFile};
use crate::lightmap::layout::stored_or_texture;
use crate::lightmap::model::{ModelFrames, model_layout, to_map};
use crate::lightmap::sample::at_vertices;
use crate::limits::MAX_BYTES;
use crate::report::figures::{FOUR_X_ERROR, PICTURE_VIEW, captioned, upright};
use crate::report::render::{Colormap, render_scalar, render_with, save_png_atomic};
use crate::rig::mesh::Mesh;
use crate::rig::uv::{Atlas, UvLayout, sample_bilinear};
use crate::rig::{Clip, Rig};

/// Texels composed per call into aprt-core: the fixed buffer an engine would stream through.
const CHUNK: usize = 4096;

/// What to compose: a sequence file or a light-map model, and the character.
pub struct ComposeSource<'a> {
    /// The input's name, for errors.
    pub name: &'a str,
    /// Its bytes.
    pub bytes: &'a [u8],
    /// The character and clip: a model's poses; for a sequence, the rendered panels.
    pub character: Option<(&'a dyn Rig, &'a Clip)>,
    /// The frame.
    pub frame: usize,
    /// Rays per vertex of the per-vertex reference.
    pub rays: usize,
}

/// One frame's transfer maps with what lighting them needs.
struct FrameMaps<'a> {
    resolution: usize,
    order: usize,
    /// `resolution²` flags: the texels holding transfer.
    filled: Vec<bool>,
    /// Bind-pose position of each filled texel, in texel order.
    positions: Vec<[f32; 3]>,
    /// `resolution² × n²`, texel-major.
    map: Vec<f32>,
    /// The light-map UVs the input stores; `None`: the character's texture UVs.
    layout: Option<UvLayout>,
    /// The model's irradiance rig, which lights the texels when present.
    rig: Option<IrradianceRig<'a>>,
}

/// Bytes a texel costs the preview beside its `n²` f32 transfer values: its filled flag, lit
/// RGB (f32), luminance, the atlas's ring, sample and bind position (a model's), and the
/// picture's RGB twice (the map's panel and the captioned figure).
const PREVIEW_BYTES_PER_TEXEL: u64 = 1 + 12 + 4 + 1 + 20 + 12 + 3 + 3;

/// Refuses a preview of a `resolution`² map at SH order `order` (of the input called `name`)
/// that would hold more than the run's budget, before any of it is allocated: the preview
/// holds the whole map, several times over.
fn check_preview_memory(name: &str, resolution: usize, order: usize) -> Result<()> {
    let per_texel = 4 * (order * order) as u64 + PREVIEW_BYTES_PER_TEXEL;
    let needed = (resolution as u64).pow(2).saturating_mul(per_texel);
    if needed > MAX_BYTES {
        bail!(
            "{name}: composing its {resolution}x{resolution} light map at SH order {order} would hold {}; one run holds at most {}: bake or train at a lower --resolution",
            crate::bake::budget::bytes(needed),
            crate::bake::budget::bytes(MAX_BYTES)
        );
    }
    Ok(())
}

/// Frame `frame` of a sequence file.
fn sequence_frame(name: &str, bytes: &[u8], frame: usize) -> Result<FrameMaps<'static>> {
    let file = ShlmFile::parse(bytes).with_context(|| format!("{name}: invalid sequence"))?;
    if frame >= file.frames() {
        bail!("--frame {frame}: {name} holds {} frames", file.frames());
    }
    let (r, order) = (file.resolution(), file.order());
    check_preview_memory(name, r, order)?;
    let mut map = vec![0.0f32; r * r * order * order];
    file.decode_frame(frame, &mut map)?;
    Ok(FrameMaps {
        resolution: r,
        order,
        filled: file.filled(),
        positions: file.positions().to_vec(),
        map,
        layout: file.layout().cloned(),
        rig: None,
    })
}

/// A light-map model's maps at frame `frame` of the clip, lit at the bind positions of the
/// rig's atlas at the model's resolution.
fn model_frame<'a>(
    name: &str,
    bytes: &'a [u8],
    rig: &dyn Rig,
    clip: &Clip,
    frame: usize,
) -> Result<FrameMaps<'a>> {
    let Some(pose) = clip.frames.get(frame) else {
        bail!(
            "--frame {frame}: clip {} has {} frames",
            clip.name,
            clip.frames.len()
        );
    };
    let one = Clip {
        frames: vec![pose.clone()],
        ..clip.clone()
    };
    let model = ModelFrames::new(bytes, name, rig, &one)?;
    let (r, order) = (model.resolution, model.order);
    check_preview_memory(name, r, order)?;
    let rows = model.predict(0..1)?;
    let map = to_map(&rows[0], &model.texels, r, order * order);
    let stored = model_layout(bytes, name)?;
    let layout = stored_or_texture(stored.as_ref(), rig, name)?;
    let atlas = Atlas::build(&layout, &rig.bind_mesh().triangles, r)?;
    Ok(FrameMaps {
        resolution: r,
        order,
        filled: atlas.filled(),
        positions: texel_positions(&atlas, rig.bind_mesh()),
        map,
        layout: stored,
        rig: aprt_core::Model::parse(bytes)?.irradiance_rig(),
    })
}

/// The RGB light map (`resolution²` texels, black where no transfer is) of `maps` under
/// `lights`: the filled texels streamed through aprt-core [`CHUNK`] at a time, lit through
/// the maps' irradiance rig (its vectors projected once, the root at the origin) when they
/// have one, else by each light at each texel.
fn light_map(maps: &FrameMaps<'_>, lights: &[Light]) -> Result<Vec<Rgb>> {
    let n2 = maps.order * maps.order;
    let texels: Vec<usize> = (0..maps.filled.len()).filter(|&t| maps.filled[t]).collect();
    if texels.len() != maps.positions.len() {
        bail!(
            "{} filled texels but {} positions",
            texels.len(),
            maps.positions.len()
        );
    }
    let composer = aprt_core::LightMap::new(maps.order)?;
    let mut out = vec![[0.0f32; 3]; maps.filled.len()];
    let mut transfer = vec![0.0f32; CHUNK * n2];
    let mut rgb = [[0.0f32; 3]; CHUNK];
    let placement = Placement::IDENTITY;
    let vectors = match &maps.rig {
        Some(rig) => {
            let mut vectors = vec![[0.0f32; 3]; rig.vectors() * n2];
            rig.vectors_from_lights(maps.order, &placement, lights, &[], &mut vectors)?;
            vectors
        }
        None => Vec::new(),
    };
    for (chunk, positions) in texels.chunks(CHUNK).zip(maps.positions.chunks(CHUNK)) {
        for (i, &t) in chunk.iter().enumerate() {
            transfer[i * n2..][..n2].copy_from_slice(&maps.map[t * n2..][..n2]);
        }
        let (k, lit) = (chunk.len(), &mut rgb[..chunk.len()]);
        match &maps.rig {
            Some(rig) => composer.compose_rig(
                &transfer[..k * n2],
                rig,
                &vectors,
                &placement,
                positions,
                lit,
            )?,
            None => composer.compose_lights(&transfer[..k * n2], positions, lights, &[], lit)?,
        }
        for (&t, &c) in chunk.iter().zip(&rgb[..k]) {
            out[t] = c;
        }
    }
    Ok(out)
}

/// The light map as a picture, shading 0..1 as black to white per channel, upscaled (nearest)
/// to the panels' height.
fn map_image(map: &[Rgb], resolution: usize) -> RgbImage {
    let r = resolution as u32;
    let image = RgbImage::from_fn(r, r, |x, y| {
        let c = map[(y * r + x) as usize];
        Pixel(c.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8))
    });
    let size = PANEL.1.max(r);
    imageops::resize(&image, size, size, imageops::FilterType::Nearest)
}

/// Each vertex's shading from its ray-traced transfer on `posed`, each vertex lit at its
/// bind-pose position as the texels are.
fn per_vertex_shading(
    posed: &Mesh,
    bind: &Mesh,
    order: usize,
    rays: usize,
    lights: &[Light],
) -> Result<Vec<f32>> {
    let settings = BakeSettings {
        order,
        rays,
        bounces: 0,
        albedo: 0.0,
        shadows: true,
    };
    let transfer = bake_pose(posed, &settings)?;
    let mut rgb = vec![[0.0f32; 3]; bind.vertex_count()];
    aprt_core::LightMap::new(order)?.compose_lights(
        &transfer,
        &bind.positions,
        lights,
        &[],
        &mut rgb,
    )?;
    Ok(rgb.into_iter().map(luminance).collect())
}

/// Panel size, as the other figures'.
const PANEL: (u32, u32) = (360, 480);

/// The character at the frame rendered with the light map, its per-vertex ray-traced shading,
/// and 4× their difference at the vertices; and the mean and largest difference in 8-bit
/// grey levels of the displayed shading (luminance).
fn character_panels(
    (rig, clip): (&dyn Rig, &Clip),
    source: &ComposeSource<'_>,
    maps: &FrameMaps,
    lit: &[Rgb],
    lights: &[Light],
) -> Result<(Vec<RgbImage>, f64, f64)> {
    let frame = source.frame;
    let Some(pose) = clip.frames.get(frame) else {
        bail!(
            "--frame {frame}: clip {} has {} frames",
            clip.name,
            clip.frames.len()
        );
    };
    let layout = stored_or_texture(maps.layout.as_ref(), rig, source.name)?;
    let bind = rig.bind_mesh();
    let posed = rig.pose(pose)?;
    let shown = upright(&posed, rig.up());
    let r = maps.resolution;
    let grey: Vec<f32> = lit.iter().map(|&c| luminance(c)).collect();
    let (w, h) = PANEL;
    let textured = render_with(&shown, PICTURE_VIEW, w, h, |tri, bary| {
        let uv = layout.corners[tri];
        let at = [0, 1].map(|k| (0..3).map(|c| bary[c] * uv[c][k]).sum::<f32>());
        let mut v = [0.0f32];
        sample_bilinear(&grey, r, 1, at, &mut v);
        Colormap::Grey.color(v[0])
    })?;
    let truth = per_vertex_shading(&posed, bind, maps.order, source.rays, lights)?;
    let uvs = layout.vertex_uvs(&bind.triangles, bind.vertex_count());
    let sampled = at_vertices(&grey, r, 1, &uvs);
    let errors: Vec<f32> = sampled
        .iter()
        .zip(&truth)
        .map(|(a, b)| (a - b).abs())
        .collect();
    let mean = errors.iter().map(|&e| f64::from(e)).sum::<f64>() / errors.len().max(1) as f64;
    let max = errors.iter().copied().fold(0.0f32, f32::max);
    let shown_errors: Vec<f32> = errors.iter().map(|e| 4.0 * e).collect();
    let panels = vec![
        textured,
        render_scalar(&shown, &truth, PICTURE_VIEW, w, h, Colormap::Grey)?,
        render_scalar(
            &shown,
            &shown_errors,
            PICTURE_VIEW,
            w,
            h,
            Colormap::Error { max: 1.0 },
        )?,
    ];
    Ok((panels, 255.0 * mean, 255.0 * f64::from(max)))
}

/// Writes the preview of `source` under `lights` to `path`: the light map, and with a
/// character the frame rendered with it | per-vertex ray-traced shading | 4× error. Returns a
/// line saying what was drawn.
pub fn save_preview(path: &Path, source: &ComposeSource<'_>, lights: &[Light]) -> Result<String> {
    let maps = if source.bytes.starts_with(MAGIC) {
        sequence_frame(source.name, source.bytes, source.frame)?
    } else {
        let Some((rig, clip)) = source.character else {
            bail!(
                "{} is a model: give its character and clip (--gltf/--bvh/--builtin, --clip) or its OBJ sequence (--obj-seq with --angles) for the pose",
                source.name
            );
        };
        model_frame(source.name, source.bytes, rig, clip, source.frame)?
    };
    let lit = light_map(&maps, lights)?;
    let mut panels = vec![map_image(&lit, maps.resolution)];
    let mut line = format!("light map, {r}x{r} texels", r = maps.resolution);
    if let Some(rig) = &maps.rig {
        line.push_str(&format!(
            ", lit through its {} irradiance rig ({} SH vectors)",
            crate::irradiance_rig::RigKind::of(rig),
            rig.vectors()
        ));
    }
    let map_title = format!("light map ({r}x{r} texels)", r = maps.resolution);
    let mut titles = vec![map_title.as_str()];
    let mut key = None;
    if let Some(character) = source.character {
        let (more, mean, max) = character_panels(character, source, &maps, &lit, lights)?;
        panels.extend(more);
        line.push_str(&format!(
            " | rendered with it | per-vertex ray-traced | 4x error (at the vertices {mean:.2} grey levels mean, {max:.1} max)"
        ));
        titles.extend(["rendered with it", "per-vertex ray-traced", "4× error"]);
        key = Some(FOUR_X_ERROR);
    }
    save_png_atomic(path, &captioned(&panels, &titles, key)?)?;
    Ok(line)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::irradiance_rig::RigKind;
    use crate::irradiance_rig::fit::fit_irradiance_rig;
    use crate::rig::character::Character;
    use aprt_core::{DirectionalLight, PointLight};

    /// A map of the built-in human's bind vertices as texels (every other one), each an
    /// unoccluded clamped-cosine lobe about its normal, lit through a gradient rig fitted to
    /// the human and directly by each light at each texel: a directional light's radiance is
    /// the same everywhere, which the rig's constant term holds exactly, so the two agree to
    /// f32 rounding; a point light beside the character varies in ways a gradient cannot
    /// follow, so they differ (the rig is not simply ignored).
    #[test]
    fn a_rig_lights_a_map_as_its_lights_do_where_it_is_exact() {
        let human = Character::builtin();
        let bind = human.bind_mesh();
        let order = 3;
        let n2 = order * order;
        let kind: RigKind = "gradient".parse().unwrap();
        let section = fit_irradiance_rig(kind, std::slice::from_ref(bind), order).unwrap();
        let rig = IrradianceRig::parse(&section).unwrap();
        let texels: Vec<usize> = (0..bind.vertex_count()).step_by(2).collect();
        let resolution = (texels.len() as f64).sqrt().ceil() as usize;
        let mut map = vec![0.0f32; resolution * resolution * n2];
        for (t, &v) in texels.iter().enumerate() {
            aprt_core::clamped_cosine(order, bind.normals[v], &mut map[t * n2..][..n2]).unwrap();
        }
        let maps = |rig| FrameMaps {
            resolution,
            order,
            filled: (0..resolution * resolution)
                .map(|t| t < texels.len())
                .collect(),
            positions: texels.iter().map(|&v| bind.positions[v]).collect(),
            map: map.clone(),
            layout: None,
            rig,
        };
        let difference = |light: Light| {
            let direct = light_map(&maps(None), &[light]).unwrap();
            let rigged = light_map(&maps(Some(rig)), &[light]).unwrap();
            let scale = direct.iter().flatten().fold(0.0f32, |m, v| m.max(v.abs()));
            let worst = direct
                .iter()
                .flatten()
                .zip(rigged.iter().flatten())
                .fold(0.0f32, |m, (a, b)| m.max((a - b).abs()));
            worst / scale
        };
        let sun = Light::Directional(DirectionalLight {
            direction: [0.3, 0.9, 0.2],
            irradiance: [1.0, 0.8, 0.6],
        });
        let exact = difference(sun);
        assert!(exact < 1e-4, "directional: {exact}");
        let lamp = Light::Point(PointLight {
            position: [0.6, 0.0, 1.0],
            intensity: [1.0; 3],
        });
        let approximate = difference(lamp);
        assert!(
            approximate > 100.0 * exact.max(1e-6),
            "point: {approximate}"
        );
    }
}
