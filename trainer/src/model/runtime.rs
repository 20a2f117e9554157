//! The trainer's view of a written model: evaluation through `aprt-core`, exactly as an
//! engine would run it, a description of the blob for `aprt inspect`, and what an irradiance
//! rig costs the core per frame on a static mesh.

use aprt_core::format::read_header;
use std::time::{Duration, Instant};

use aprt_core::{
    Basis, Encoding, Frame, Light, LitWeights, MAX_COEFFS, Model, Placement, PoseWeights,
    ProxyFrame, Rgb, RigLitWeights, Rotation, SectionKind, clamped_cosine,
};

use crate::irradiance_rig::fit::{FittedRig, rig_vectors};
use crate::limits::MAX_EXTENT;
use crate::model::export::{Precision, encode_model_with_rig};
use crate::model::{LinearModel, VertexBasis};
use crate::rig::bone_frames::BoneFrames;
use crate::rig::mesh::Mesh;
use crate::text::shown;

/// Per-vertex transfer (`v × n²`, vertex-major) for each pose, through `aprt-core`, in the
/// model's frame (world, or each vertex's bone).
pub fn predict_transfer(
    blob: &[u8],
    poses: &[Vec<f64>],
) -> Result<Vec<Vec<f32>>, aprt_core::Error> {
    let model = Model::parse(blob)?;
    let info = model.info();
    let mut pose = Box::new(PoseWeights::new());
    poses
        .iter()
        .map(|angles| {
            let angles: Vec<f32> = angles.iter().map(|&a| a as f32).collect();
            model.set_pose(&angles, &mut pose)?;
            let mut out = vec![0.0f32; info.vertices() * info.coeffs()];
            model.transfer(&pose, 0, &mut out)?;
            Ok(out)
        })
        .collect()
}

/// The bytes of the model's occluder proxies (its `Proxies` section), when it has them.
pub fn proxies_section(blob: &[u8]) -> Result<Option<&[u8]>, aprt_core::Error> {
    let model = Model::parse(blob)?;
    if !model.info().has_proxies() {
        return Ok(None);
    }
    section(blob, SectionKind::Proxies)
}

/// The bytes of the section of `kind` of a blob the core validated, when it has one.
fn section(blob: &[u8], kind: SectionKind) -> Result<Option<&[u8]>, aprt_core::Error> {
    let header = read_header(blob)?;
    Ok(header
        .sections
        .iter()
        .find(|e| e.kind == kind.tag())
        .and_then(|e| {
            let start = usize::try_from(e.offset).ok()?;
            blob.get(start..start.checked_add(usize::try_from(e.len).ok()?)?)
        }))
}

/// Largest gain of an irradiance rig's SH vector, `Σ_i |L_ki|` over its samples' weights: far
/// beyond a fitted rig's (about 1 for a constant rig, the inverse of the character's size for
/// a gradient), and small enough that lighting of any radiance below 10²⁶ maps to finite
/// vectors.
pub const MAX_RIG_GAIN: f64 = 1e12;

/// Why [`describe`] refused a blob.
#[derive(Debug, thiserror::Error)]
pub enum BlobError {
    /// The core refused it.
    #[error(transparent)]
    Core(#[from] aprt_core::Error),
    /// An irradiance rig point (centre, half-width, radius or sample) beyond any character.
    #[error(
        "irradiance rig: its {what} holds {value:e}, beyond the {MAX_EXTENT:e} of any character"
    )]
    RigExtent {
        /// Which value.
        what: String,
        /// The value.
        value: f32,
    },
    /// An irradiance rig vector whose weights could turn plain lighting into infinities.
    #[error(
        "irradiance rig: the weights of its SH vector {vector} sum to {gain:e} in magnitude, beyond {MAX_RIG_GAIN:e}: lighting it maps would overflow"
    )]
    RigGain {
        /// The vector.
        vector: usize,
        /// `Σ_i |L_ki|`.
        gain: f64,
    },
}

/// Refuses an irradiance rig whose values, finite as the core requires, no fit makes: a point
/// beyond [`MAX_EXTENT`] or a vector's gain beyond [`MAX_RIG_GAIN`]. The core maps lighting
/// through them to infinities (`compose` failed "lighting coefficient 0 is NaN or infinite",
/// naming neither the file nor the rig) or to shading off by 10³⁸.
fn check_rig_range(blob: &[u8], rig: &aprt_core::IrradianceRig<'_>) -> Result<(), BlobError> {
    let beyond = |p: [f32; 3]| p.into_iter().find(|v| f64::from(v.abs()) > MAX_EXTENT);
    let fixed = [
        ("centre", rig.centre()),
        ("half-widths", rig.half()),
        ("radius", [rig.radius(); 3]),
    ];
    for (what, point) in fixed {
        if let Some(value) = beyond(point) {
            return Err(BlobError::RigExtent {
                what: what.into(),
                value,
            });
        }
    }
    for i in 0..rig.samples() {
        if let Some(value) = beyond(rig.sample(i)) {
            return Err(BlobError::RigExtent {
                what: format!("sample {i}"),
                value,
            });
        }
    }
    let bytes = section(blob, SectionKind::IrradianceRig)?.unwrap_or_default();
    let n = rig.samples();
    // The fit matrix follows the 44-byte prelude, the error table and the samples (FORMAT.md).
    let matrix = bytes
        .get(44 + 8 * rig.table_len() + 12 * n..)
        .unwrap_or_default();
    for (vector, row) in matrix.chunks_exact(4 * n).enumerate() {
        let gain: f64 = row
            .chunks_exact(4)
            .map(|w| f64::from(f32::from_le_bytes([w[0], w[1], w[2], w[3]]).abs()))
            .sum();
        if gain > MAX_RIG_GAIN {
            return Err(BlobError::RigGain { vector, gain });
        }
    }
    Ok(())
}

/// The bone of each vertex, for bone-frame models; `None` for world-frame models.
pub fn bone_frames(blob: &[u8]) -> Result<Option<BoneFrames>, aprt_core::Error> {
    let model = Model::parse(blob)?;
    let Frame::Bones { count } = model.info().frame() else {
        return Ok(None);
    };
    let mut vertex_bone = vec![0u16; model.info().vertices()];
    model.vertex_bones(0, &mut vertex_bone)?;
    Ok(Some(BoneFrames {
        count: count as usize,
        vertex_bone,
    }))
}

/// Per-vertex shading `Σ_c L_c t_c` for one pose and world SH lighting, through `aprt-core`
/// (`rotations`: the bones' skinning rotations of a bone-frame model, empty otherwise).
pub fn predict_shading(
    blob: &[u8],
    angles: &[f64],
    rotations: &[Rotation],
    lighting: &[f32],
) -> Result<Vec<f32>, aprt_core::Error> {
    let model = Model::parse(blob)?;
    let angles: Vec<f32> = angles.iter().map(|&a| a as f32).collect();
    let mut pose = Box::new(PoseWeights::new());
    model.set_pose(&angles, &mut pose)?;
    let mut lit = Box::new(LitWeights::new());
    model.light(&pose, lighting, rotations, &mut lit)?;
    let mut out = vec![0.0f32; model.info().vertices()];
    model.shade(&lit, 0, &mut out)?;
    Ok(out)
}

/// One section as `aprt inspect` shows it.
#[derive(Debug, serde::Serialize)]
pub struct SectionInfo {
    /// Kind name, or `unknown(tag)`.
    pub kind: String,
    /// `f32` or `f16`.
    pub encoding: String,
    /// Byte offset.
    pub offset: u64,
    /// Byte length.
    pub bytes: u64,
}

/// What `aprt inspect` shows: the header, the dimensions and the bytes per section.
#[derive(Debug, serde::Serialize)]
pub struct BlobInfo {
    /// Format version.
    pub version: u32,
    /// SH order n.
    pub order: usize,
    /// Vertex count.
    pub vertices: usize,
    /// Entries of the pose vector (JSON key `joints`, which scripts read).
    #[serde(rename = "joints")]
    pub pose_len: usize,
    /// Pose features the projection sees: the angles and their cosines, where flagged.
    pub features: usize,
    /// k_a.
    pub pose_dims: usize,
    /// k_v (vertices for the identity basis).
    pub coef_dims: usize,
    /// `stored` or `identity` (the full linear model).
    pub basis: String,
    /// The fit's Tikhonov parameter.
    pub alpha: f32,
    /// Bones of a bone-frame model (0: world frame).
    pub bones: usize,
    /// Total blob bytes.
    pub bytes: usize,
    /// Scratch bytes a streaming reader needs (one block of vertex rows).
    pub scratch_bytes: usize,
    /// Values the runtime's pose weights hold for this model.
    pub pose_weights: usize,
    /// Values the runtime's lighting weights hold for this model.
    pub lit_weights: usize,
    /// Bytes of one frame of uncompressed f32 PRT (`v · n² · 4`), for comparison.
    pub frame_prt_bytes: usize,
    /// The section table.
    pub sections: Vec<SectionInfo>,
    /// Names of the pose entries, in pose-vector order (empty when the blob records none).
    pub angle_names: Vec<String>,
    /// The irradiance rig the model carries, if any.
    pub irradiance_rig: Option<RigInfo>,
    /// The texel atlas of a light-map model (whose rows are texels), if it records one.
    pub texel_atlas: Option<AtlasInfo>,
}

/// What `inspect` says of a light-map model's texel atlas.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct AtlasInfo {
    /// The map is `resolution × resolution` texels.
    pub resolution: u32,
    /// Rows of the model, one texel each.
    pub rows: usize,
    /// Triangles whose corner UVs the atlas records (0: none).
    pub triangles: usize,
}

/// What `inspect` says of a model's irradiance rig.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct RigInfo {
    /// The kind, as `--rig` spells it.
    pub kind: String,
    /// SH vectors per frame.
    pub sh_vectors: usize,
    /// Surface samples the lights are projected at per frame.
    pub samples: usize,
    /// Values the runtime's rig lighting weights hold for this model.
    pub rig_lit_weights: usize,
}

impl RigInfo {
    fn of(rig: &aprt_core::IrradianceRig<'_>, info: &aprt_core::ModelInfo) -> RigInfo {
        RigInfo {
            kind: crate::irradiance_rig::RigKind::of(rig).to_string(),
            sh_vectors: rig.vectors(),
            samples: rig.samples(),
            rig_lit_weights: info.rig_lit_weights_len(rig.vectors()),
        }
    }
}

/// Validates `blob` completely (the core's checks, and an irradiance rig's range) and
/// describes it.
pub fn describe(blob: &[u8]) -> Result<BlobInfo, BlobError> {
    let model = Model::parse(blob)?;
    if let Some(rig) = model.irradiance_rig() {
        check_rig_range(blob, &rig)?;
    }
    let info = model.info();
    let header = read_header(blob)?;
    let sections = header
        .sections
        .iter()
        .map(|e| SectionInfo {
            kind: match SectionKind::from_tag(e.kind) {
                SectionKind::Unknown(tag) => format!("unknown({tag})"),
                kind => format!("{kind:?}"),
            },
            encoding: match Encoding::from_tag(e.encoding) {
                Some(Encoding::F32) => "f32".into(),
                Some(Encoding::F16) => "f16".into(),
                Some(Encoding::I8) => "i8".into(),
                None => format!("unknown({})", e.encoding),
            },
            offset: e.offset,
            bytes: e.len,
        })
        .collect();
    Ok(BlobInfo {
        version: aprt_core::FORMAT_VERSION,
        order: info.order(),
        vertices: info.vertices(),
        pose_len: info.pose_len(),
        features: info.feature_len(),
        pose_dims: info.pose_dims(),
        coef_dims: info.coef_dims(),
        basis: match info.basis() {
            Basis::Stored => "stored".into(),
            Basis::Identity => "identity".into(),
        },
        alpha: info.alpha(),
        bones: info.bones(),
        bytes: blob.len(),
        scratch_bytes: info.scratch_bytes(),
        pose_weights: info.pose_weights_len(),
        lit_weights: info.lit_weights_len(),
        frame_prt_bytes: info.vertices() * info.coeffs() * 4,
        sections,
        angle_names: model.angle_names().iter().map(str::to_owned).collect(),
        irradiance_rig: model.irradiance_rig().map(|r| RigInfo::of(&r, info)),
        texel_atlas: model.texel_atlas().map(|a| AtlasInfo {
            resolution: a.resolution(),
            rows: a.rows(),
            triangles: a.triangles(),
        }),
    })
}

impl std::fmt::Display for BlobInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "aprt model, format version {}", self.version)?;
        writeln!(
            f,
            "  SH order        {} ({} coefficients)",
            self.order,
            self.order * self.order
        )?;
        writeln!(f, "  vertices        {}", self.vertices)?;
        writeln!(f, "  joint angles    {}", self.pose_len)?;
        let cosines = self.features - self.pose_len;
        if cosines > 0 {
            writeln!(
                f,
                "  pose features   {} (the angles and {cosines} of their cosines)",
                self.features
            )?;
        }
        writeln!(f, "  pose dims k_a   {}", self.pose_dims)?;
        writeln!(
            f,
            "  coef dims k_v   {} ({} basis)",
            self.coef_dims, self.basis
        )?;
        writeln!(f, "  alpha           {:.6e}", self.alpha)?;
        if self.bones > 0 {
            writeln!(f, "  bone frames     {}", self.bones)?;
        }
        writeln!(
            f,
            "  bytes           {} ({:.1}% of one frame of f32 PRT, {} bytes)",
            self.bytes,
            100.0 * self.bytes as f64 / self.frame_prt_bytes as f64,
            self.frame_prt_bytes
        )?;
        writeln!(
            f,
            "  runtime state   {} bytes of streaming scratch, {} pose and {} lighting weights",
            self.scratch_bytes, self.pose_weights, self.lit_weights
        )?;
        if !self.angle_names.is_empty() {
            // Escaped and cut: the names are the blob's, whatever bytes it holds.
            let names: Vec<String> = self.angle_names.iter().map(|n| shown(n)).collect();
            writeln!(f, "  pose entries    {}", names.join(" "))?;
        }
        if let Some(rig) = &self.irradiance_rig {
            writeln!(
                f,
                "  irradiance rig  {}: {} SH vectors from {} samples, {} rig lighting weights",
                rig.kind, rig.sh_vectors, rig.samples, rig.rig_lit_weights
            )?;
        }
        if let Some(atlas) = &self.texel_atlas {
            let r = u64::from(atlas.resolution);
            write!(
                f,
                "  texel atlas     {r} x {r}: {} rows are texels ({:.1}% of the map)",
                atlas.rows,
                100.0 * atlas.rows as f64 / (r * r) as f64
            )?;
            match atlas.triangles {
                0 => writeln!(f)?,
                t => writeln!(f, ", corner UVs of {t} triangles")?,
            }
        }
        writeln!(f, "  sections:")?;
        for s in &self.sections {
            writeln!(
                f,
                "    {:<16} {:<4} offset {:>10}  {:>10} bytes",
                s.kind, s.encoding, s.offset, s.bytes
            )?;
        }
        Ok(())
    }
}

/// One frame of rig lighting through aprt-core, as an engine runs it ([`CoreFrame`] with no
/// environment): the model's pose weights, each light's share from the rig's error table
/// (`target` grey levels, `band`), the rig's SH vectors from the lights' rig shares, rig-lit
/// shading of every vertex at its own position, and the rest of each light per vertex
/// through the vertex's transfer. `positions` are the posed vertices in the world, which is
/// the root frame here. A model with occluder proxies then loses what they block under each
/// vertex's lighting, posed by `geometry`: each bone's skinning matrix and the posed normals.
/// Returns the RGB shading and each light's rig share.
#[allow(clippy::too_many_arguments)]
pub fn predict_rig_shading(
    blob: &[u8],
    angles: &[f64],
    rotations: &[Rotation],
    positions: &[[f32; 3]],
    geometry: (&[aprt_core::Skinning], &[[f32; 3]]),
    lights: &[aprt_core::Light],
    target: f32,
    band: f32,
) -> Result<(Vec<[f32; 3]>, Vec<f32>), aprt_core::Error> {
    let angles: Vec<f32> = angles.iter().map(|&a| a as f32).collect();
    let inputs = FrameInputs {
        angles: &angles,
        rotations,
        positions,
        skinning: geometry.0,
        normals: geometry.1,
        environment: &[],
        lights,
        centre: [0.0; 3],
        target,
        band,
    };
    let mut frame = CoreFrame::new(blob, lights.len())?;
    if !frame.has_rig() {
        return Err(aprt_core::Error::NoIrradianceRig);
    }
    frame.run(&inputs)?;
    Ok((frame.rgb, frame.shares))
}

/// What one frame hands the core besides the model: the pose, the posed character and the
/// lighting.
pub struct FrameInputs<'a> {
    /// The model's pose entries.
    pub angles: &'a [f32],
    /// The bones' skinning rotations (a bone-frame model), else empty.
    pub rotations: &'a [Rotation],
    /// Posed vertex positions in the world (the root frame).
    pub positions: &'a [[f32; 3]],
    /// Each bone's skinning matrix, for a model with occluder proxies.
    pub skinning: &'a [aprt_core::Skinning],
    /// Posed vertex normals, for a model with occluder proxies.
    pub normals: &'a [[f32; 3]],
    /// Distant SH radiance at the model's order (n² RGB), or empty.
    pub environment: &'a [Rgb],
    /// The lights.
    pub lights: &'a [Light],
    /// Where a model without a rig has its lights projected (the character's centre).
    pub centre: [f32; 3],
    /// The rig's error target (grey levels) that splits each light between rig and vertex.
    pub target: f32,
    /// The split's transition band.
    pub band: f32,
}

/// One frame of a model through aprt-core, as an engine runs it, with every buffer it needs
/// allocated once, so that timing repeated frames times only the core's work (one function
/// for what `train --scene` and `aprt report` quote, and for the rig's predictions):
/// - with an irradiance rig: set the pose; split each light by its rig share; the rig's SH
///   vectors from the environment and the lights' rig shares; push them through the pose
///   weights; shade every vertex (RGB) at its position; add each light's per-vertex rest
///   through the vertex's transfer.
/// - without: set the pose; the environment and every light projected at the centre, as
///   luminance (the report's errors are luminance); push it through the pose weights; shade
///   every vertex.
///
/// A model with occluder proxies then poses them and takes off what they block.
pub struct CoreFrame<'m> {
    model: Model<'m>,
    rig: Option<aprt_core::IrradianceRig<'m>>,
    pose: Box<PoseWeights>,
    lit: Box<LitWeights>,
    rig_lit: Vec<f32>,
    vectors: Vec<Rgb>,
    in_rig: Vec<Light>,
    rest: Vec<f32>,
    per_vertex: Vec<Light>,
    centre_sh: Vec<Rgb>,
    luminance: Vec<f32>,
    proxies: Box<ProxyFrame>,
    /// Each light's rig share, after a frame with a rig.
    pub shares: Vec<f32>,
    /// RGB shading per vertex, after a frame with a rig.
    pub rgb: Vec<Rgb>,
    /// Luminance shading per vertex, after a frame without a rig.
    pub grey: Vec<f32>,
}

impl<'m> CoreFrame<'m> {
    /// The frame's buffers for `blob` under `lights` lights.
    pub fn new(blob: &'m [u8], lights: usize) -> Result<CoreFrame<'m>, aprt_core::Error> {
        let model = Model::parse(blob)?;
        let info = *model.info();
        let rig = model.irradiance_rig();
        let (n2, v) = (info.coeffs(), info.vertices());
        let k = rig.as_ref().map_or(0, |r| r.vectors());
        Ok(CoreFrame {
            rig_lit: vec![0.0; rig.as_ref().map_or(0, |_| info.rig_lit_weights_len(k))],
            vectors: vec![[0.0; 3]; k * n2],
            rgb: vec![[0.0; 3]; if rig.is_some() { v } else { 0 }],
            grey: vec![0.0; if rig.is_some() { 0 } else { v }],
            model,
            rig,
            pose: Box::new(PoseWeights::new()),
            lit: Box::new(LitWeights::new()),
            in_rig: Vec::with_capacity(lights),
            rest: vec![0.0; lights],
            per_vertex: Vec::with_capacity(lights),
            centre_sh: vec![[0.0; 3]; n2],
            luminance: vec![0.0; n2],
            proxies: Box::new(ProxyFrame::new()),
            shares: vec![0.0; lights],
        })
    }

    /// Whether the model carries an irradiance rig.
    pub fn has_rig(&self) -> bool {
        self.rig.is_some()
    }

    /// Runs one frame of `inputs`.
    pub fn run(&mut self, inputs: &FrameInputs<'_>) -> Result<(), aprt_core::Error> {
        self.model.set_pose(inputs.angles, &mut self.pose)?;
        match self.rig {
            Some(rig) => self.rig_frame(&rig, inputs),
            None => self.centre_frame(inputs),
        }
    }

    /// The frame under the model's rig, the rest of each light per vertex.
    fn rig_frame(
        &mut self,
        rig: &aprt_core::IrradianceRig<'m>,
        inputs: &FrameInputs<'_>,
    ) -> Result<(), aprt_core::Error> {
        let (model, place) = (&self.model, Placement::IDENTITY);
        let order = model.info().order();
        self.in_rig.clear();
        for ((light, share), rest) in inputs
            .lights
            .iter()
            .zip(&mut self.shares)
            .zip(&mut self.rest)
        {
            *share = rig.share_of(light, &place, inputs.target, inputs.band);
            *rest = 1.0 - *share;
            self.in_rig.push(light.scaled(*share));
        }
        let env = inputs.environment;
        rig.vectors_from_lights(order, &place, &self.in_rig, env, &mut self.vectors)?;
        let mut lit = RigLitWeights::new(&mut self.rig_lit);
        model.light_rig(&self.pose, &self.vectors, inputs.rotations, &mut lit)?;
        model.shade_rig(&lit, rig, &place, inputs.positions, 0, &mut self.rgb)?;
        let (lights, rest, at) = (inputs.lights, &self.rest, inputs.positions);
        model.shade_lights(
            &self.pose,
            inputs.rotations,
            lights,
            rest,
            at,
            0,
            &mut self.rgb,
        )?;
        if !model.info().has_proxies() {
            return Ok(());
        }
        model.pose_proxies(inputs.skinning, &mut self.proxies)?;
        self.per_vertex.clear();
        let scaled = lights.iter().zip(rest).map(|(l, &r)| l.scaled(r));
        self.per_vertex.extend(scaled);
        let (vectors, per_vertex, out) = (&self.vectors, &self.per_vertex, &mut self.rgb);
        let mut lighting = [[0.0f32; 3]; MAX_COEFFS];
        model.occlusions(&self.proxies, at, inputs.normals, 0, |i, d| {
            let l = &mut lighting[..d.len()];
            rig.lighting_at(vectors, &place, at[i], l);
            // A vertex on a point light gets nothing from it, as in `shade_lights`.
            for light in per_vertex {
                let _ = light.add_radiance_sh(order, at[i], l);
            }
            for (o, k) in out[i].iter_mut().zip(0..3) {
                *o -= d.iter().zip(l.iter()).map(|(d, c)| d * c[k]).sum::<f32>();
            }
        })
    }

    /// The frame under the lighting projected at the centre, shaded as luminance.
    fn centre_frame(&mut self, inputs: &FrameInputs<'_>) -> Result<(), aprt_core::Error> {
        let model = &self.model;
        let order = model.info().order();
        self.centre_sh.fill([0.0; 3]);
        for (o, e) in self.centre_sh.iter_mut().zip(inputs.environment) {
            *o = *e;
        }
        for (index, light) in inputs.lights.iter().enumerate() {
            light
                .add_radiance_sh(order, inputs.centre, &mut self.centre_sh)
                .map_err(|reason| aprt_core::Error::BadLight { index, reason })?;
        }
        for (y, c) in self.luminance.iter_mut().zip(&self.centre_sh) {
            *y = crate::lighting::luminance(*c);
        }
        model.light(&self.pose, &self.luminance, inputs.rotations, &mut self.lit)?;
        model.shade(&self.lit, 0, &mut self.grey)?;
        if model.info().has_proxies() {
            model.pose_proxies(inputs.skinning, &mut self.proxies)?;
            let (at, normals) = (inputs.positions, inputs.normals);
            model.occlude(
                &self.proxies,
                &self.luminance,
                at,
                normals,
                0,
                &mut self.grey,
            )?;
        }
        Ok(())
    }

    /// Median µs of this frame over repeated runs (about a tenth of a second), after one run
    /// whose refusal is the error, never a cost of 0 µs.
    pub fn median_us(&mut self, inputs: &FrameInputs<'_>) -> Result<f64, aprt_core::Error> {
        self.run(inputs)?;
        Ok(median_us(|| {
            let _ = self.run(inputs);
        }))
    }
}

/// Microseconds per frame in aprt-core, median of repeated frames.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct FrameCost {
    /// The lights projected at the rig's samples and mapped to its SH vectors.
    pub rig_vectors: f64,
    /// The vectors pushed through the transfer and every vertex shaded.
    pub shade: f64,
    /// The lights' per-vertex shares, through each vertex's transfer.
    pub analytic: f64,
    /// All three together.
    pub total: f64,
}

/// A world-frame model whose vertex `j` has the transfer of an unoccluded point of normal
/// `normals[j]`, the clamped cosine (one pose entry, no pose dimensions): what the core shades
/// a static mesh with, so a bare mesh's rig is timed on the core's own per-frame path.
pub fn static_model(normals: &[[f32; 3]], order: usize) -> LinearModel {
    let (n2, v) = (order * order, normals.len());
    let mut weights = vec![0.0f64; n2 * v];
    let mut t = [0.0f32; MAX_COEFFS];
    for (j, n) in normals.iter().enumerate() {
        if clamped_cosine(order, *n, &mut t[..n2]).is_ok() {
            for c in 0..n2 {
                weights[c * v + j] = f64::from(t[c]);
            }
        }
    }
    LinearModel {
        order,
        vertices: v,
        pose_len: 1,
        pose_mean: vec![0.0],
        pose_projection: Vec::new(),
        weights,
        basis: VertexBasis::Identity,
        alpha: 0.0,
        bones: None,
        angle_names: vec!["static".into()],
        bounds: None,
        cosines: Vec::new(),
        proxies: None,
    }
}

/// Median µs of `f` over repeated runs: at least 5, up to a tenth of a second or 1,000.
pub fn median_us(mut f: impl FnMut()) -> f64 {
    let mut times = Vec::new();
    let start = Instant::now();
    while times.len() < 5 || (start.elapsed() < Duration::from_millis(100) && times.len() < 1000) {
        let t = Instant::now();
        f();
        times.push(t.elapsed().as_secs_f64() * 1e6);
    }
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

/// The core's cost per frame of `lights` on `mesh` (in the rig's root frame) lit through
/// `fitted`, each light split by its rig share (`shares`, as the rig's evaluation chose): the
/// rig's vectors, the rig-lit shading of a static model of `mesh`'s normals, and the
/// per-vertex shares. Each step runs once before it is timed, so a refusal of the core is an
/// error here, never a cost of 0 µs.
pub fn rig_frame_cost(
    fitted: &FittedRig,
    mesh: &Mesh,
    lights: &[Light],
    shares: &[f32],
    order: usize,
) -> anyhow::Result<FrameCost> {
    let in_rig: Vec<Light> = lights
        .iter()
        .zip(shares)
        .map(|(l, &s)| l.scaled(s))
        .collect();
    let rest: Vec<f32> = shares.iter().map(|s| 1.0 - s).collect();
    let blob = encode_model_with_rig(
        &static_model(&mesh.normals, order),
        Precision::F32,
        Some(&fitted.bytes()),
    )?;
    let model = Model::parse(&blob)?;
    let rig = model
        .irradiance_rig()
        .ok_or_else(|| anyhow::anyhow!("the static model written with the rig has no rig"))?;
    let mut pose = PoseWeights::new();
    model.set_pose(&[0.0], &mut pose)?;
    let mut vectors = rig_vectors(&rig, &in_rig, order, &Placement::IDENTITY)?;
    let rig_vectors_us = median_us(|| {
        vectors = rig_vectors(&rig, &in_rig, order, &Placement::IDENTITY).unwrap_or_default();
    });
    let mut buffer = vec![0.0f32; model.info().rig_lit_weights_len(rig.vectors())];
    let mut shading = vec![[0.0f32; 3]; mesh.vertex_count()];
    let mut shade = || {
        let mut lit = RigLitWeights::new(&mut buffer);
        model.light_rig(&pose, &vectors, &[], &mut lit)?;
        let placement = &Placement::IDENTITY;
        model.shade_rig(&lit, &rig, placement, &mesh.positions, 0, &mut shading)
    };
    shade()?;
    let shade_us = median_us(|| {
        let _ = shade();
    });
    let analytic_us = match rest.iter().any(|&w| w > 0.0) {
        true => {
            let mut per_vertex =
                || model.shade_lights(&pose, &[], lights, &rest, &mesh.positions, 0, &mut shading);
            per_vertex()?;
            median_us(|| {
                let _ = per_vertex();
            })
        }
        false => 0.0,
    };
    Ok(FrameCost {
        rig_vectors: rig_vectors_us,
        shade: shade_us,
        analytic: analytic_us,
        total: rig_vectors_us + shade_us + analytic_us,
    })
}
