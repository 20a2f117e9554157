//! The reader and evaluator driven by arbitrary bytes: what the cargo-fuzz target `reader` runs
//! for hours and `tests/tests/hostile.rs` runs on thousands of crafted and mutated blobs.
//!
//! [`exercise`] asserts, rather than merely survives: the resident and streamed readers give
//! the same verdict; invalid inputs (NaN angles, wrong lengths, bad rotations, vertex ranges
//! past the end, scratch too small) give their specific error; streamed evaluation is
//! bit-identical to resident evaluation for any buffer that is large enough; any vertex range is
//! the matching slice of the whole; and whatever the core accepts evaluates to what the blob
//! stores, by the f64 reference. A panic anywhere is a finding.

use aprt_core::blob::{Error, Frame};
use aprt_core::{BlobSource, LitWeights, Model, PoseWeights, SliceSource};

use crate::Streamed;
use crate::decode::decode;
use crate::reference;

/// Bytes of a serialised [`Probe`].
pub const PROBE_BYTES: usize = 48;

/// The evaluation inputs of one fuzz case, decoded from a fixed-size prefix of the input so the
/// rest is the blob exactly (seed blobs are written after [`Probe::to_bytes`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Probe {
    /// Joint angle `j` is `angles[j % 4]`; NaN and infinities included, to be refused.
    pub angles: [f32; 4],
    /// SH lighting coefficient `c` is `lighting[c % 4]`.
    pub lighting: [f32; 4],
    /// Bone `b`'s world rotation turns about axis `b % 3` by `turn · (b + 1)` radians.
    pub turn: f32,
    /// Gives every bone a stretching matrix instead, to be refused.
    pub skew: bool,
    /// First vertex of the range evaluated on its own: `first % (v + 9)`, or with `far` near
    /// `usize::MAX` so that `first + count` overflows.
    pub first: u32,
    /// Vertices in that range: `count % (v + 9)`, so ranges end before, at and past the end.
    pub count: u32,
    /// See `first`.
    pub far: bool,
    /// Streamed evaluation gets `Model::scratch_bytes() + scratch_delta` bytes of scratch.
    pub scratch_delta: i16,
    /// Streamed opening gets `open_scratch % 64` bytes of scratch.
    pub open_scratch: u8,
}

impl Probe {
    /// Finite inputs, a small rotation, an interior vertex range and the least scratch.
    pub const GENTLE: Probe = Probe {
        angles: [0.25, -0.5, 1.0, 0.125],
        lighting: [1.0, 0.5, -0.25, 0.125],
        turn: 0.3,
        skew: false,
        first: 1,
        count: 5,
        far: false,
        scratch_delta: 0,
        open_scratch: 4,
    };

    /// Decodes the first [`PROBE_BYTES`] of `bytes` (missing bytes read as zero).
    pub fn from_bytes(bytes: &[u8]) -> Probe {
        let mut b = [0u8; PROBE_BYTES];
        let n = bytes.len().min(PROBE_BYTES);
        b[..n].copy_from_slice(&bytes[..n]);
        let f = |i: usize| f32::from_le_bytes(b[i..i + 4].try_into().unwrap());
        let u = |i: usize| u32::from_le_bytes(b[i..i + 4].try_into().unwrap());
        Probe {
            angles: std::array::from_fn(|k| f(4 * k)),
            lighting: std::array::from_fn(|k| f(16 + 4 * k)),
            turn: f(32),
            first: u(36),
            count: u(40),
            scratch_delta: i16::from_le_bytes([b[44], b[45]]),
            open_scratch: b[46],
            skew: b[47] & 1 != 0,
            far: b[47] & 2 != 0,
        }
    }

    /// The bytes [`Probe::from_bytes`] reads back as `self`.
    pub fn to_bytes(&self) -> [u8; PROBE_BYTES] {
        let mut b = [0u8; PROBE_BYTES];
        let floats = self.angles.iter().chain(&self.lighting).chain([&self.turn]);
        for (chunk, x) in b.chunks_exact_mut(4).zip(floats) {
            chunk.copy_from_slice(&x.to_le_bytes());
        }
        b[36..40].copy_from_slice(&self.first.to_le_bytes());
        b[40..44].copy_from_slice(&self.count.to_le_bytes());
        b[44..46].copy_from_slice(&self.scratch_delta.to_le_bytes());
        b[46] = self.open_scratch;
        b[47] = u8::from(self.skew) | u8::from(self.far) << 1;
        b
    }

    /// Splits a fuzz input into its probe and its blob.
    pub fn split(data: &[u8]) -> (Probe, &[u8]) {
        let n = data.len().min(PROBE_BYTES);
        (Probe::from_bytes(&data[..n]), &data[n..])
    }

    fn rotation(&self, bone: usize) -> [[f32; 3]; 3] {
        if self.skew {
            return [[2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        }
        let (s, c) = (self.turn * (bone + 1) as f32).sin_cos();
        let (i, j) = [(0, 1), (1, 2), (2, 0)][bone % 3];
        let mut r = [[0.0f32; 3]; 3];
        r[3 - i - j][3 - i - j] = 1.0;
        (r[i][i], r[i][j], r[j][i], r[j][j]) = (c, -s, s, c);
        r
    }

    /// The same inputs with every non-finite value replaced by zero, and true rotations.
    fn sanitised(&self) -> Probe {
        let finite = |x: f32| if x.is_finite() { x } else { 0.0 };
        Probe {
            angles: self.angles.map(finite),
            lighting: self.lighting.map(finite),
            // Turns of up to 256 bones must stay finite.
            turn: if (self.turn * 256.0).is_finite() {
                self.turn
            } else {
                0.0
            },
            skew: false,
            ..*self
        }
    }
}

/// One evaluation of every vertex by the core, with the inputs it was given.
#[derive(Clone, Debug, PartialEq)]
pub struct Evaluation {
    /// Joint angles.
    pub angles: Vec<f32>,
    /// World SH lighting.
    pub lighting: Vec<f32>,
    /// Bones' world rotations (empty for world-frame models).
    pub rotations: Vec<[[f32; 3]; 3]>,
    /// `Model::transfer`, `v × n²`.
    pub transfer: Vec<f32>,
    /// `Model::shade`.
    pub shading: Vec<f32>,
    /// `Model::vertex_bones`.
    pub bones: Vec<u16>,
}

/// Reads `blob` resident and streamed and, when valid, evaluates it with `probe`'s inputs and
/// checks everything listed in the module documentation (panicking on a violation). Returns
/// the reader's error, or the evaluation of every vertex at the probe's inputs made finite.
pub fn exercise(blob: &[u8], probe: &Probe) -> Result<Evaluation, Error> {
    let parsed = Model::parse(blob);
    let streamed = Model::open(&mut Streamed::new(blob), &mut [0u8; 4]);
    assert_eq!(streamed, parsed, "streamed and resident readers disagree");
    let mut scratch = vec![0u8; probe.open_scratch as usize % 64];
    let opened = Model::open(&mut Streamed::new(blob), &mut scratch);
    assert!(
        opened == parsed
            || scratch.len() < 4 && matches!(opened, Err(Error::BufferTooSmall { .. })),
        "open with {} bytes of scratch: {opened:?}, parse: {parsed:?}",
        scratch.len()
    );
    let model = parsed?;

    check_refusals(&model, blob, probe);
    let inputs = probe.sanitised();
    let eval = evaluate(&model, &mut SliceSource(blob), &inputs, &mut [])
        .expect("a valid model evaluates finite inputs from a resident blob");
    let len = model.scratch_bytes();
    let len = len.saturating_add_signed(inputs.scratch_delta as isize);
    check_streamed(&model, blob, &inputs, &eval, len);
    check_range(&model, blob, probe, &eval);
    let stored = decode(blob).expect("FORMAT.md reads every blob the core accepts");
    reference::assert_matches(&stored, &eval, |_| 0.0);
    Ok(eval)
}

fn angles(model: &Model, probe: &Probe) -> Vec<f32> {
    (0..model.joints()).map(|j| probe.angles[j % 4]).collect()
}

fn lighting(model: &Model, probe: &Probe) -> Vec<f32> {
    (0..model.order() * model.order())
        .map(|c| probe.lighting[c % 4])
        .collect()
}

fn rotations(model: &Model, probe: &Probe) -> Vec<[[f32; 3]; 3]> {
    match model.frame() {
        Frame::World => Vec::new(),
        Frame::Bones { count } => (0..count as usize).map(|b| probe.rotation(b)).collect(),
    }
}

/// A pose set and lit from a probe's inputs.
struct Lit {
    angles: Vec<f32>,
    lighting: Vec<f32>,
    rotations: Vec<[[f32; 3]; 3]>,
    pose: PoseWeights,
    lit: LitWeights,
}

fn set_and_light<S: BlobSource>(
    model: &Model,
    src: &mut S,
    probe: &Probe,
    scratch: &mut [u8],
) -> Result<Lit, Error> {
    let (angles, lighting, rotations) = (
        angles(model, probe),
        lighting(model, probe),
        rotations(model, probe),
    );
    let mut pose = PoseWeights::default();
    model.set_pose(src, &angles, scratch, &mut pose)?;
    let mut lit = LitWeights::default();
    match model.frame() {
        Frame::World => model.light(&pose, &lighting, &mut lit)?,
        Frame::Bones { .. } => model.light_skinned(&pose, &lighting, &rotations, &mut lit)?,
    }
    Ok(Lit {
        angles,
        lighting,
        rotations,
        pose,
        lit,
    })
}

/// Sets the pose, lights it and evaluates every vertex.
fn evaluate<S: BlobSource>(
    model: &Model,
    src: &mut S,
    probe: &Probe,
    scratch: &mut [u8],
) -> Result<Evaluation, Error> {
    let l = set_and_light(model, src, probe, scratch)?;
    let v = model.vertices();
    let mut transfer = vec![0.0f32; v * l.lighting.len()];
    model.transfer(src, &l.pose, 0, &mut transfer, scratch)?;
    let mut shading = vec![0.0f32; v];
    model.shade(src, &l.lit, 0, &mut shading, scratch)?;
    let mut bones = vec![0u16; v];
    model.vertex_bones(src, 0, &mut bones, scratch)?;
    Ok(Evaluation {
        angles: l.angles,
        lighting: l.lighting,
        rotations: l.rotations,
        transfer,
        shading,
        bones,
    })
}

/// Raw probe inputs: non-finite values, wrong lengths, skewed rotations and the wrong lighting
/// call for the frame each get their own error, and never a panic.
fn check_refusals(model: &Model, blob: &[u8], probe: &Probe) {
    let src = &mut SliceSource(blob);
    let (angles, lighting, rotations) = (
        angles(model, probe),
        lighting(model, probe),
        rotations(model, probe),
    );
    let finite = |xs: &[f32]| xs.iter().all(|x| x.is_finite());
    let mut pose = PoseWeights::default();
    let a = angles.len();
    assert_eq!(
        model.set_pose(src, &angles[..a - 1], &mut [], &mut pose),
        Err(Error::WrongLength {
            expected: a,
            found: a - 1
        })
    );
    let mut lit = LitWeights::default();
    assert_eq!(
        model.light(&pose, &[], &mut lit).unwrap_err(),
        match model.frame() {
            Frame::World => Error::ShapeMismatch,
            Frame::Bones { .. } => Error::FrameMismatch,
        },
        "lighting before any pose"
    );
    let set = model.set_pose(src, &angles, &mut [], &mut pose);
    if !finite(&angles) {
        assert_eq!(set, Err(Error::NonFiniteInput));
        return;
    }
    set.unwrap();
    let bad_rotation = probe.skew || !rotations.iter().flatten().all(|r| finite(r));
    let lit_result = match model.frame() {
        Frame::World => {
            assert_eq!(
                model.light_skinned(&pose, &lighting, &rotations, &mut lit),
                Err(Error::FrameMismatch)
            );
            model.light(&pose, &lighting, &mut lit)
        }
        Frame::Bones { .. } => {
            assert_eq!(
                model.light(&pose, &lighting, &mut lit),
                Err(Error::FrameMismatch)
            );
            assert!(matches!(
                model.light_skinned(&pose, &lighting, &rotations[1..], &mut lit),
                Err(Error::WrongLength { .. })
            ));
            match model.light_skinned(&pose, &lighting, &rotations, &mut lit) {
                Err(Error::BadRotation) if finite(&lighting) => {
                    assert!(bad_rotation, "a true rotation refused: {rotations:?}");
                    return;
                }
                result => result,
            }
        }
    };
    if !finite(&lighting) {
        assert_eq!(lit_result, Err(Error::NonFiniteInput));
        return;
    }
    lit_result.unwrap();
    assert!(
        !bad_rotation || rotations.is_empty(),
        "a skewed rotation accepted"
    );
    let n2 = lighting.len();
    if n2 > 1 {
        assert!(matches!(
            model.transfer(src, &pose, 0, &mut [0.0; 1], &mut []),
            Err(Error::WrongLength { .. })
        ));
    }
}

/// Streamed evaluation with `len` bytes of scratch: bit-identical to resident evaluation when
/// it succeeds, which it must when the scratch is at least `Model::scratch_bytes`.
fn check_streamed(model: &Model, blob: &[u8], inputs: &Probe, resident: &Evaluation, len: usize) {
    let least = model.scratch_bytes();
    let mut scratch = vec![0u8; len];
    match evaluate(model, &mut Streamed::new(blob), inputs, &mut scratch) {
        Ok(streamed) => assert!(
            bits(&streamed) == bits(resident),
            "streamed evaluation with {len} bytes of scratch differs"
        ),
        Err(Error::BufferTooSmall { needed }) => assert!(
            len < least && needed > len,
            "scratch of {len} bytes refused (least {least}, needed {needed})"
        ),
        Err(e) => panic!("streamed evaluation failed: {e:?}"),
    }
}

/// `check_streamed` for every scratch length in `lens`, against one resident evaluation of
/// the valid blob `blob` at the probe's inputs made finite.
pub fn check_streaming(blob: &[u8], probe: &Probe, lens: impl IntoIterator<Item = usize>) {
    let model = Model::parse(blob).expect("a valid blob");
    let inputs = probe.sanitised();
    let resident = evaluate(&model, &mut SliceSource(blob), &inputs, &mut []).unwrap();
    for len in lens {
        check_streamed(&model, blob, &inputs, &resident, len);
    }
}

/// The evaluation's numbers as bits, so NaN compares equal to itself and -0 differs from +0.
fn bits(e: &Evaluation) -> (Vec<u32>, Vec<u32>, &[u16]) {
    let b = |xs: &[f32]| xs.iter().map(|x| x.to_bits()).collect();
    (b(&e.transfer), b(&e.shading), &e.bones)
}

/// The probe's vertex range: the matching slice of the whole when inside the model, a
/// `VertexRange` error otherwise, for shading, transfer and bone indices alike.
fn check_range(model: &Model, blob: &[u8], probe: &Probe, whole: &Evaluation) {
    let v = model.vertices();
    let first = if probe.far {
        usize::MAX - probe.first as usize % 8
    } else {
        probe.first as usize % (v + 9)
    };
    let count = probe.count as usize % (v + 9);
    let inside = first.checked_add(count).is_some_and(|end| end <= v);
    let n2 = model.order() * model.order();
    let src = &mut SliceSource(blob);
    let Lit { pose, lit, .. } = set_and_light(model, src, &probe.sanitised(), &mut []).unwrap();
    let refused = Err(Error::VertexRange { first, count });
    let (mut shading, mut transfer, mut bones) = (
        vec![0.0f32; count],
        vec![0.0f32; count * n2],
        vec![0u16; count],
    );
    let results = [
        model.shade(src, &lit, first, &mut shading, &mut []),
        model.transfer(src, &pose, first, &mut transfer, &mut []),
        model.vertex_bones(src, first, &mut bones, &mut []),
    ];
    if !inside {
        assert!(
            results.iter().all(|r| *r == refused),
            "{results:?} for {first}+{count} of {v}"
        );
        return;
    }
    assert!(results.iter().all(Result::is_ok), "{results:?}");
    let same = |a: &[f32], b: &[f32]| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits());
    assert!(same(&shading, &whole.shading[first..first + count]));
    assert!(same(
        &transfer,
        &whole.transfer[first * n2..(first + count) * n2]
    ));
    assert_eq!(bones, whole.bones[first..first + count]);
}
