//! Shared support for the integration tests, the benchmarks and the cargo-fuzz targets in
//! `fuzz/`: deterministic random models, a non-resident blob source, and the fuzz harnesses
//! themselves, so `cargo test` runs the same checks as the fuzzer, only for less time.

pub mod decode;
pub mod edit;
pub mod harness;
pub mod quadrature;
pub mod reference;
pub mod samples;
pub mod spec;

use aprt_core::{
    BlobSource, Error, LitWeights, Model, ModelInfo, PoseWeights, Rotation, SourceError,
    StreamedModel,
};
use aprt_trainer::{LinearModel, VertexBasis};

/// A source that is not resident: every read copies, as from flash or a file, and is counted.
pub struct Streamed<'a> {
    /// The blob.
    pub bytes: &'a [u8],
    /// Reads so far.
    pub reads: usize,
}

impl<'a> Streamed<'a> {
    /// Streams `bytes`.
    pub fn new(bytes: &'a [u8]) -> Self {
        Streamed { bytes, reads: 0 }
    }
}

impl BlobSource for Streamed<'_> {
    fn len(&self) -> u64 {
        self.bytes.len() as u64
    }
    fn read_at(&mut self, offset: u64, buf: &mut [u8]) -> Result<(), SourceError> {
        self.reads += 1;
        let start = usize::try_from(offset).map_err(|_| SourceError)?;
        let end = start.checked_add(buf.len()).ok_or(SourceError)?;
        buf.copy_from_slice(self.bytes.get(start..end).ok_or(SourceError)?);
        Ok(())
    }
}

/// The per-frame calls of a resident and a streamed model, so one test drives both.
pub trait Eval {
    /// `info()`.
    fn info(&self) -> &ModelInfo;
    /// `set_pose`.
    fn set_pose(&mut self, angles: &[f32], pose: &mut PoseWeights) -> Result<(), Error>;
    /// `light`.
    fn light(
        &mut self,
        pose: &PoseWeights,
        lighting: &[f32],
        bones: &[Rotation],
        lit: &mut LitWeights,
    ) -> Result<(), Error>;
    /// `shade`.
    fn shade(&mut self, lit: &LitWeights, first: usize, out: &mut [f32]) -> Result<(), Error>;
    /// `transfer`.
    fn transfer(&mut self, pose: &PoseWeights, first: usize, out: &mut [f32]) -> Result<(), Error>;
    /// `vertex_bones`.
    fn vertex_bones(&mut self, first: usize, out: &mut [u16]) -> Result<(), Error>;
}

macro_rules! forward_eval {
    () => {
        fn info(&self) -> &ModelInfo {
            Self::info(self)
        }
        fn set_pose(&mut self, angles: &[f32], pose: &mut PoseWeights) -> Result<(), Error> {
            Self::set_pose(self, angles, pose)
        }
        fn light(
            &mut self,
            pose: &PoseWeights,
            lighting: &[f32],
            bones: &[Rotation],
            lit: &mut LitWeights,
        ) -> Result<(), Error> {
            Self::light(self, pose, lighting, bones, lit)
        }
        fn shade(&mut self, lit: &LitWeights, first: usize, out: &mut [f32]) -> Result<(), Error> {
            Self::shade(self, lit, first, out)
        }
        fn transfer(
            &mut self,
            pose: &PoseWeights,
            first: usize,
            out: &mut [f32],
        ) -> Result<(), Error> {
            Self::transfer(self, pose, first, out)
        }
        fn vertex_bones(&mut self, first: usize, out: &mut [u16]) -> Result<(), Error> {
            Self::vertex_bones(self, first, out)
        }
    };
}

impl Eval for Model<'_> {
    forward_eval!();
}

impl<S: BlobSource> Eval for StreamedModel<'_, S> {
    forward_eval!();
}

/// Deterministic pseudo-random values in [-1, 1) (xorshift64).
pub fn noise(seed: u64, n: usize) -> Vec<f64> {
    let mut s = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        })
        .collect()
}

/// A model of the given shape with random contents; `coef_dims: None` is the identity basis.
pub fn random_model(
    order: usize,
    vertices: usize,
    pose_len: usize,
    pose_dims: usize,
    coef_dims: Option<usize>,
) -> LinearModel {
    let n2 = order * order;
    LinearModel {
        order,
        vertices,
        pose_len,
        pose_mean: noise(1, pose_len),
        pose_projection: noise(2, pose_dims * pose_len),
        weights: noise(3, n2 * (pose_dims + 1) * coef_dims.unwrap_or(vertices)),
        basis: match coef_dims {
            Some(k) => VertexBasis::Stored {
                coef_dims: k,
                data: noise(4, vertices * k),
            },
            None => VertexBasis::Identity,
        },
        alpha: 0.5,
        bones: None,
        angle_names: (0..pose_len).map(|i| format!("joint{i}")).collect(),
    }
}
