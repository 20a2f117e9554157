//! Shared support for the integration tests, the benchmarks and the cargo-fuzz targets in
//! `fuzz/`: deterministic random models, a non-resident blob source, and the fuzz harnesses
//! themselves, so `cargo test` runs the same checks as the fuzzer, only for less time.

pub mod decode;
pub mod edit;
pub mod golden;
pub mod harness;
pub mod loaders;
pub mod quadrature;
pub mod readers;
pub mod reference;
pub mod samples;
pub mod spec;
mod timing;

pub use timing::{interleaved_seconds, median_ratio};

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

/// Declares [`Eval`] with the calls listed, and implements it for both models by calling
/// their inherent methods of the same names.
macro_rules! eval_trait {
    ($($(#[$doc:meta])* fn $name:ident($($arg:ident: $ty:ty),*);)*) => {
        /// The per-frame calls of a resident and a streamed model, so one test drives both.
        pub trait Eval {
            /// `info()`.
            fn info(&self) -> &ModelInfo;
            $($(#[$doc])* fn $name(&mut self, $($arg: $ty),*) -> Result<(), Error>;)*
        }
        eval_trait!(@impl [] Model<'_>; $($name($($arg: $ty),*);)*);
        eval_trait!(@impl [S: BlobSource] StreamedModel<'_, S>; $($name($($arg: $ty),*);)*);
    };
    (@impl [$($generics:tt)*] $model:ty; $($name:ident($($arg:ident: $ty:ty),*);)*) => {
        impl<$($generics)*> Eval for $model {
            fn info(&self) -> &ModelInfo {
                Self::info(self)
            }
            $(fn $name(&mut self, $($arg: $ty),*) -> Result<(), Error> {
                Self::$name(self, $($arg),*)
            })*
        }
    };
}

eval_trait! {
    /// `set_pose`.
    fn set_pose(angles: &[f32], pose: &mut PoseWeights);
    /// `light`.
    fn light(pose: &PoseWeights, lighting: &[f32], bones: &[Rotation], lit: &mut LitWeights);
    /// `shade`.
    fn shade(lit: &LitWeights, first: usize, out: &mut [f32]);
    /// `transfer`.
    fn transfer(pose: &PoseWeights, first: usize, out: &mut [f32]);
    /// `vertex_bones`.
    fn vertex_bones(first: usize, out: &mut [u16]);
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
        bounds: None,
        cosines: Vec::new(),
        proxies: None,
    }
}

/// `model` with the cosine features of the entries `flags` sets: its pose mean and projection
/// drawn again over the longer feature vector.
pub fn with_cosines(mut model: LinearModel, flags: &[bool]) -> LinearModel {
    let ka = model.pose_dims();
    model.cosines = flags.to_vec();
    let f = model.feature_len();
    model.pose_mean = noise(5, f);
    model.pose_projection = noise(6, ka * f);
    model
}

/// Median seconds per call of `f` over nine batches, each sized from a first pass lasting a
/// tenth of `budget`: the benchmarks' one timer, so every ratio they print is timed alike.
pub fn median_seconds(budget: std::time::Duration, mut f: impl FnMut()) -> f64 {
    f();
    let start = std::time::Instant::now();
    let mut calls = 0u32;
    while start.elapsed() < budget / 10 {
        f();
        calls += 1;
    }
    let batch = calls.max(1);
    let mut samples: Vec<f64> = (0..9)
        .map(|_| {
            let t = std::time::Instant::now();
            for _ in 0..batch {
                f();
            }
            t.elapsed().as_secs_f64() / batch as f64
        })
        .collect();
    samples.sort_by(f64::total_cmp);
    samples[4]
}

/// The rotation by `angle` radians about `axis` (any non-zero length; Rodrigues), row-major, as
/// the core's bone rotations are given.
pub fn axis_angle(axis: [f32; 3], angle: f32) -> [[f32; 3]; 3] {
    let n = (axis.iter().map(|a| a * a).sum::<f32>()).sqrt();
    let [x, y, z] = axis.map(|a| a / n);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

/// `fuzz/corpus/<target>`: the fuzz target's seeds, written by the `write_corpus` example.
pub fn fuzz_corpus(target: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/corpus")
        .join(target)
}
