//! The trainer's view of a written model: evaluation through `aprt-core`, exactly as an
//! engine would run it, and a description of the blob for `aprt inspect`.

use aprt_core::blob::{ANGLE_NAMES_TAG, Basis, Encoding, Frame, SectionKind, read_header};
use aprt_core::{LitWeights, Model, PoseWeights, SliceSource};

use crate::model::BoneFrames;

/// Per-vertex transfer (`v × n²`, vertex-major) for each pose, through `aprt-core`, in the
/// model's frame (world, or each vertex's bone).
pub fn predict_transfer(
    blob: &[u8],
    poses: &[Vec<f64>],
) -> Result<Vec<Vec<f32>>, aprt_core::Error> {
    let model = Model::parse(blob)?;
    let n2 = model.order() * model.order();
    let mut pose = PoseWeights::default();
    poses
        .iter()
        .map(|angles| {
            let angles: Vec<f32> = angles.iter().map(|&a| a as f32).collect();
            model.set_pose(&mut SliceSource(blob), &angles, &mut [], &mut pose)?;
            let mut out = vec![0.0f32; model.vertices() * n2];
            model.transfer(&mut SliceSource(blob), &pose, 0, &mut out, &mut [])?;
            Ok(out)
        })
        .collect()
}

/// The bone of each vertex, for bone-frame models; `None` for world-frame models.
pub fn bone_frames(blob: &[u8]) -> Result<Option<BoneFrames>, aprt_core::Error> {
    let model = Model::parse(blob)?;
    let Frame::Bones { count } = model.frame() else {
        return Ok(None);
    };
    let mut vertex_bone = vec![0u16; model.vertices()];
    model.vertex_bones(&mut SliceSource(blob), 0, &mut vertex_bone, &mut [])?;
    Ok(Some(BoneFrames {
        count: count as usize,
        vertex_bone,
    }))
}

/// Pushes world lighting through the pose weights, rotating it into each bone's frame first
/// for bone-frame models (`rotations`: each bone's world rotation, row-major; empty for
/// world-frame models).
pub fn light(
    model: &Model,
    pose: &PoseWeights,
    lighting: &[f32],
    rotations: &[[[f32; 3]; 3]],
    lit: &mut LitWeights,
) -> Result<(), aprt_core::Error> {
    match model.frame() {
        Frame::World => model.light(pose, lighting, lit),
        Frame::Bones { .. } => model.light_skinned(pose, lighting, rotations, lit),
    }
}

/// Per-vertex shading `Σ_c L_c t_c` for one pose and world SH lighting, through `aprt-core`.
pub fn predict_shading(
    blob: &[u8],
    angles: &[f64],
    rotations: &[[[f32; 3]; 3]],
    lighting: &[f32],
) -> Result<Vec<f32>, aprt_core::Error> {
    let model = Model::parse(blob)?;
    let angles: Vec<f32> = angles.iter().map(|&a| a as f32).collect();
    let mut pose = PoseWeights::default();
    model.set_pose(&mut SliceSource(blob), &angles, &mut [], &mut pose)?;
    let mut lit = LitWeights::default();
    light(&model, &pose, lighting, rotations, &mut lit)?;
    let mut out = vec![0.0f32; model.vertices()];
    model.shade(&mut SliceSource(blob), &lit, 0, &mut out, &mut [])?;
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
    /// Joint angles per pose.
    pub joints: usize,
    /// k_a.
    pub pose_dims: usize,
    /// k_v (vertices for the identity basis).
    pub coef_dims: usize,
    /// `stored` or `identity` (the full linear model).
    pub basis: String,
    /// The fit's Tikhonov parameter.
    pub alpha: f32,
    /// Total blob bytes.
    pub bytes: usize,
    /// Bytes of one frame of uncompressed f32 PRT (`v · n² · 4`), for comparison.
    pub frame_prt_bytes: usize,
    /// The section table.
    pub sections: Vec<SectionInfo>,
    /// Names of the pose entries, in pose-vector order (empty when the blob records none).
    pub angle_names: Vec<String>,
}

/// Validates `blob` completely and describes it.
pub fn describe(blob: &[u8]) -> Result<BlobInfo, aprt_core::Error> {
    let model = Model::parse(blob)?;
    let header = read_header(blob)?;
    let sections = header
        .sections
        .iter()
        .map(|e| SectionInfo {
            kind: match SectionKind::from_tag(e.kind) {
                Some(k) => format!("{k:?}"),
                None if e.kind == ANGLE_NAMES_TAG => "AngleNames".into(),
                None => format!("unknown({})", e.kind),
            },
            encoding: match Encoding::from_tag(e.encoding) {
                Some(Encoding::F32) => "f32".into(),
                Some(Encoding::F16) => "f16".into(),
                None => format!("unknown({})", e.encoding),
            },
            offset: e.offset,
            bytes: e.len,
        })
        .collect();
    Ok(BlobInfo {
        version: aprt_core::blob::VERSION,
        order: model.order(),
        vertices: model.vertices(),
        joints: model.joints(),
        pose_dims: model.pose_dims(),
        coef_dims: model.coef_dims(),
        basis: match model.basis() {
            Basis::Stored => "stored".into(),
            Basis::Identity => "identity".into(),
        },
        alpha: model.alpha(),
        bytes: blob.len(),
        frame_prt_bytes: model.vertices() * model.order() * model.order() * 4,
        sections,
        angle_names: crate::model::export::read_angle_names(blob).unwrap_or_default(),
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
        writeln!(f, "  joint angles    {}", self.joints)?;
        writeln!(f, "  pose dims k_a   {}", self.pose_dims)?;
        writeln!(
            f,
            "  coef dims k_v   {} ({} basis)",
            self.coef_dims, self.basis
        )?;
        writeln!(f, "  alpha           {:.6e}", self.alpha)?;
        writeln!(
            f,
            "  bytes           {} ({:.1}% of one frame of f32 PRT, {} bytes)",
            self.bytes,
            100.0 * self.bytes as f64 / self.frame_prt_bytes as f64,
            self.frame_prt_bytes
        )?;
        if !self.angle_names.is_empty() {
            writeln!(f, "  pose entries    {}", self.angle_names.join(" "))?;
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
