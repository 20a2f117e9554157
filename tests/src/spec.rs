//! Arbitrary model shapes and contents for the writer → reader round trip. One generator, an
//! `arbitrary` implementation, serves both the cargo-fuzz target `round_trip` (fuzzer bytes)
//! and the proptest in `tests/tests/roundtrip.rs` (random bytes), so what the fuzzer explores
//! for hours is what `cargo test` checks in seconds.

use aprt_core::{MAX_BONES, MAX_COEF_DIMS, MAX_LIT, MAX_ORDER, MAX_POSE_DIMS, MAX_POSE_LEN};
use aprt_trainer::{
    BoneFrames, ExportError, LinearModel, PoseBounds, Precision, VertexBasis, encode_model,
};
use arbitrary::{Arbitrary, Unstructured};

use crate::decode::decode;
use crate::harness::{Probe, exercise};
use crate::noise;
use crate::reference::{self, f16_rounding};

/// A model for the writer and the precision to write it in. Every value is exactly an f32, so
/// an f32 blob must give it back bit for bit.
#[derive(Clone, Debug)]
pub struct ModelSpec {
    /// The model, inside every limit of the format.
    pub model: LinearModel,
    /// Storage precision of the weights and per-vertex rows.
    pub precision: Precision,
}

/// Values for one section: mostly smooth noise at a random scale, sometimes the fuzzer's own
/// bits (any f32 within 2^±30, so products of four stay finite), zeros, or boundary values
/// (subnormals, f16's largest and first overflowing value, f32's largest).
fn values(u: &mut Unstructured, n: usize) -> arbitrary::Result<Vec<f64>> {
    const EDGES: [f32; 10] = [
        0.0,
        -0.0,
        1.0e-45,
        f32::MIN_POSITIVE,
        5.960_464_5e-8,
        1.000_488_3,
        65504.0,
        65520.0,
        -f32::MAX,
        1.0 / 3.0,
    ];
    Ok(match u.int_in_range(0..=11u8)? {
        0..=7 => {
            let seed = u.arbitrary::<u64>()?;
            let scale = f64::powi(2.0, u.int_in_range(-20..=8)?);
            noise(seed, n)
                .into_iter()
                .map(|x| (x * scale) as f32 as f64)
                .collect()
        }
        8 => (0..n)
            .map(|_| {
                let bits = u.arbitrary::<u32>()?;
                let exponent = ((bits >> 23) & 0xff) % 61 + 97; // 2^-30 ..= 2^30
                Ok(f32::from_bits(bits & 0x807f_ffff | exponent << 23) as f64)
            })
            .collect::<arbitrary::Result<_>>()?,
        9 => vec![0.0; n],
        _ => {
            let start = u.choose_index(EDGES.len())?;
            (0..n)
                .map(|i| EDGES[(start + i) % EDGES.len()] as f64)
                .collect()
        }
    })
}

impl<'a> Arbitrary<'a> for ModelSpec {
    fn arbitrary(u: &mut Unstructured<'a>) -> arbitrary::Result<Self> {
        // Now and then a dimension at the format's limit; otherwise small, fast shapes.
        let edge = u.ratio(1, 16)?;
        let order = u.int_in_range(1..=MAX_ORDER)?;
        let pose_len = match edge {
            true => *u.choose(&[MAX_POSE_LEN, MAX_POSE_DIMS, MAX_POSE_DIMS + 1])?,
            false => u.int_in_range(1..=12)?,
        };
        let pose_dims = u.int_in_range(0..=pose_len.min(if edge { MAX_POSE_DIMS } else { 6 }))?;
        // Now and then cosine features on some entries, within the feature limit.
        let mut cosines: Vec<bool> = if pose_len < MAX_POSE_LEN && u.arbitrary()? {
            (0..pose_len)
                .map(|_| u.arbitrary())
                .collect::<arbitrary::Result<_>>()?
        } else {
            Vec::new()
        };
        // No flag set is no section, which reads back as no flags.
        if !cosines.contains(&true) {
            cosines.clear();
        }
        let features = pose_len + cosines.iter().filter(|&&c| c).count();
        let vertices = u.int_in_range(1..=if edge { 300 } else { 40 })?;
        let coef_dims = match u.arbitrary::<bool>()? {
            true => None,
            false if edge => Some(MAX_COEF_DIMS),
            false => Some(u.int_in_range(1..=24)?),
        };
        let n2 = order * order;
        let kv = coef_dims.unwrap_or(vertices);
        let basis = match coef_dims {
            None => VertexBasis::Identity,
            Some(k) => VertexBasis::Stored {
                coef_dims: k,
                data: values(u, vertices * k)?,
            },
        };
        let bones = match u.ratio(1, 3)? {
            false => None,
            true => {
                let count = if edge {
                    MAX_BONES
                } else {
                    u.int_in_range(1..=6)?
                };
                let seed = u.arbitrary::<u64>()?;
                let vertex_bone = noise(seed, vertices)
                    .iter()
                    .map(|x| ((x + 1.0) * 0.5 * count as f64) as u16 % count as u16)
                    .collect();
                Some(BoneFrames { count, vertex_bone })
            }
        };
        let bounds = if u.arbitrary()? {
            // f32 values: the section is stored in f32.
            let n: Vec<f64> = noise(u.arbitrary::<u64>()?, 3 * pose_len)
                .iter()
                .map(|&x| x as f32 as f64)
                .collect();
            Some(PoseBounds {
                lo: n[..pose_len].iter().map(|x| -x.abs()).collect(),
                hi: n[pose_len..2 * pose_len].iter().map(|x| x.abs()).collect(),
                scale: n[2 * pose_len..].iter().map(|x| 4.0 * x.abs()).collect(),
                prior: vec![0.0; pose_len],
            })
        } else {
            None
        };
        Ok(ModelSpec {
            model: LinearModel {
                order,
                vertices,
                pose_len,
                pose_mean: values(u, features)?,
                pose_projection: values(u, pose_dims * features)?,
                weights: values(u, n2 * (pose_dims + 1) * kv)?,
                basis,
                alpha: u.int_in_range(0..=1000u16)? as f64 / 64.0,
                bones,
                bounds,
                cosines,
                proxies: None,
                angle_names: if u.arbitrary()? {
                    (0..pose_len).map(|i| format!("joint{i}.x")).collect()
                } else {
                    Vec::new()
                },
            },
            // Odd bytes f16 as before scaled bytes were drawn, so saved inputs keep theirs.
            precision: match u.arbitrary::<u8>()? {
                b if b & 1 == 1 => Precision::F16,
                b if b & 2 == 2 => Precision::I8,
                _ => Precision::F32,
            },
        })
    }
}

impl ModelSpec {
    /// Draws a spec from raw bytes (zeros once they run out).
    pub fn from_bytes(bytes: &[u8]) -> ModelSpec {
        ModelSpec::arbitrary(&mut Unstructured::new(bytes)).expect("bytes running out read as 0")
    }

    /// The model as the blob should store it: the weights and per-vertex rows rounded to the
    /// storage precision, everything else exact.
    pub fn stored(&self) -> LinearModel {
        let m = &self.model;
        let f16 = |xs: &[f64]| -> Vec<f64> {
            xs.iter()
                .map(|&x| half::f16::from_f64(x).to_f64())
                .collect()
        };
        let (weights, basis) = match (self.precision, &m.basis) {
            (Precision::F32, basis) => (m.weights.clone(), basis.clone()),
            (Precision::F16, VertexBasis::Identity) => (f16(&m.weights), VertexBasis::Identity),
            (Precision::F16, VertexBasis::Stored { coef_dims, data }) => (
                f16(&m.weights),
                VertexBasis::Stored {
                    coef_dims: *coef_dims,
                    data: f16(data),
                },
            ),
            // Identity rows are contiguous per row over the vertices; a stored basis's
            // vectors are its columns.
            (Precision::I8, VertexBasis::Identity) => (
                m.weights.chunks(m.vertices).flat_map(i8_vector).collect(),
                VertexBasis::Identity,
            ),
            (Precision::I8, VertexBasis::Stored { coef_dims, data }) => {
                let kv = *coef_dims;
                let columns: Vec<Vec<f64>> = (0..kv)
                    .map(|k| {
                        i8_vector(&data.iter().skip(k).step_by(kv).copied().collect::<Vec<_>>())
                    })
                    .collect();
                let data = (0..data.len()).map(|i| columns[i % kv][i / kv]).collect();
                (
                    m.weights.clone(),
                    VertexBasis::Stored {
                        coef_dims: kv,
                        data,
                    },
                )
            }
        };
        LinearModel {
            weights,
            basis,
            alpha: m.alpha as f32 as f64,
            ..m.clone()
        }
    }

    /// Lighting weights one frame needs: bones × row width for bone-frame models.
    fn lit_len(&self) -> usize {
        let m = &self.model;
        let width = match &m.basis {
            VertexBasis::Stored { coef_dims, .. } => *coef_dims,
            VertexBasis::Identity => m.order * m.order * (1 + m.pose_dims()),
        };
        m.bones.as_ref().map_or(0, |b| b.count * width)
    }
}

/// Writes `spec`, reads it back and evaluates it with `probe`'s inputs ([`exercise`], which
/// also compares with the f64 reference of what the blob stores). Panics unless: the writer
/// refuses only values the precision cannot represent; the reader accepts what the writer
/// writes; every value comes back exactly (f32) or rounded to nearest (f16, within
/// [`f16_rounding`]); and the evaluation equals `predict` of the unrounded model within f32
/// rounding plus the effect of the storage rounding.
pub fn round_trip(spec: &ModelSpec, probe: &Probe) {
    let blob = match encode_model(&spec.model, spec.precision) {
        Ok(blob) => blob,
        Err(ExportError::NotRepresentable { value, .. }) => {
            assert!(
                spec.precision == Precision::F16 && half::f16::from_f64(value).is_infinite(),
                "the writer refused {value} in {:?}",
                spec.precision
            );
            return;
        }
        Err(ExportError::TooLarge { what, .. }) if spec.lit_len() > MAX_LIT => {
            // The runtime lights every bone's row per frame in a fixed buffer; the writer
            // refuses what the reader would.
            assert_eq!(what, "bones × lit row width");
            return;
        }
        Err(e) => panic!("the writer refused a model inside the limits: {e}"),
    };
    assert!(
        spec.lit_len() <= MAX_LIT,
        "the writer wrote a model the runtime cannot light"
    );
    let evaluated = exercise(&blob, probe);
    let stored = decode(&blob).expect("a valid blob decodes");
    let expect = spec.stored();
    assert!(stored == expect, "stored values differ from the model's");
    // Values near f32's limit evaluate to `Overflow`, never to non-finite output.
    let eval = match evaluated {
        Err(aprt_core::Error::Overflow) => return,
        evaluated => evaluated.expect("the reader accepts every blob the writer writes"),
    };
    if spec.precision == Precision::F16 {
        let near = |q: &[f64], x: &[f64]| {
            q.iter()
                .zip(x)
                .all(|(q, x)| (q - x).abs() <= f16_rounding(*x))
        };
        assert!(near(&stored.weights, &spec.model.weights));
        if let (VertexBasis::Stored { data: q, .. }, VertexBasis::Stored { data: x, .. }) =
            (&stored.basis, &spec.model.basis)
        {
            assert!(near(q, x));
        }
    }
    // Scaled bytes are judged against what the blob stores: their rounding depends on the
    // vector's scale, not on the value, and `i8_vector` states it exactly.
    match spec.precision {
        Precision::F32 => reference::assert_matches(&spec.model, &eval, |_| 0.0),
        Precision::F16 => reference::assert_matches(&spec.model, &eval, f16_rounding),
        Precision::I8 => reference::assert_matches(&expect, &eval, |_| 0.0),
    }
}

/// One vector stored as scaled bytes, as `FORMAT.md` states it: `s = max |v| / 127` rounded to
/// f32, each value `s · round(v / s)` (0 when `s` is 0).
pub fn i8_vector(v: &[f64]) -> Vec<f64> {
    let s = f64::from((v.iter().fold(0.0f64, |m, x| m.max(x.abs())) / 127.0) as f32);
    v.iter()
        .map(|&x| {
            if s == 0.0 {
                0.0
            } else {
                s * (x / s).round().clamp(-127.0, 127.0)
            }
        })
        .collect()
}
