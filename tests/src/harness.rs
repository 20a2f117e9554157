//! The reader and evaluator driven by arbitrary bytes: what the cargo-fuzz target `reader` runs
//! for hours and `tests/tests/hostile.rs` runs on thousands of crafted and mutated blobs.
//!
//! [`exercise`] asserts, rather than merely survives: the resident and streamed readers give
//! the same verdict; invalid inputs (NaN angles, wrong lengths, bad rotations, vertex ranges
//! past the end, scratch too small) give their specific error; streamed evaluation is
//! bit-identical to resident evaluation for any buffer that is large enough; any vertex range is
//! the matching slice of the whole; and whatever the core accepts evaluates to what the blob
//! stores, by the f64 reference. A panic anywhere is a finding.

use aprt_core::{
    Error, Frame, Input, IrradianceRig, Light, LitWeights, Model, ModelInfo, Placement, PointLight,
    PoseWeights, ProxyFrame, RigLitWeights, Rotation, Skinning, SphereLight, StreamedModel,
};

use crate::decode::decode;
use crate::{Eval, Streamed, reference};

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
    /// Streamed evaluation gets `ModelInfo::scratch_bytes() + scratch_delta` bytes of scratch.
    pub scratch_delta: i16,
    /// A streamed opening gets `open_scratch % 64` bytes of scratch.
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

    fn rotation(&self, bone: usize) -> Rotation {
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
    /// Bones' skinning rotations (empty for world-frame models).
    pub rotations: Vec<Rotation>,
    /// `transfer`, `v × n²`.
    pub transfer: Vec<f32>,
    /// `shade`.
    pub shading: Vec<f32>,
    /// `vertex_bones`.
    pub bones: Vec<u16>,
    /// How the blob stores its per-vertex values.
    pub encoding: aprt_core::Encoding,
}

/// Reads `blob` resident and streamed and, when valid, evaluates it with `probe`'s inputs and
/// checks everything listed in the module documentation (panicking on a violation). Returns
/// the reader's error, or the evaluation of every vertex at the probe's inputs made finite.
pub fn exercise(blob: &[u8], probe: &Probe) -> Result<Evaluation, Error> {
    let parsed = Model::parse(blob).map(|m| *m.info());
    // The sizes read from the header are those of the model, and a header refused is the
    // blob refused.
    let needs = StreamedModel::needs(Streamed::new(blob));
    match (parsed, needs) {
        (Ok(info), needs) => assert_eq!(needs.map(|n| n.scratch_bytes), Ok(info.scratch_bytes())),
        (Err(e), Err(refused)) => assert_eq!(refused, e, "the header's verdict"),
        (Err(_), Ok(_)) => {}
    }
    let least = needs.map_or(4, |n| n.scratch_bytes);
    let streamed =
        StreamedModel::open(Streamed::new(blob), &mut vec![0u8; least]).map(|m| *m.info());
    assert_eq!(streamed, parsed, "streamed and resident readers disagree");
    let mut scratch = vec![0u8; probe.open_scratch as usize % 64];
    let opened = StreamedModel::open(Streamed::new(blob), &mut scratch).map(|m| *m.info());
    // A buffer smaller than the header asks for is refused with that size before the
    // sections are read; one that suffices gets the blob validated.
    let expected = match needs {
        Ok(n) if scratch.len() < n.scratch_bytes => Err(Error::BufferTooSmall {
            needed: n.scratch_bytes,
        }),
        _ => parsed,
    };
    assert_eq!(
        opened,
        expected,
        "open with {} bytes of scratch",
        scratch.len()
    );
    let model = Model::parse(blob)?;

    check_refusals(&model, probe);
    let inputs = probe.sanitised();
    let eval = match evaluate(&mut { model }, &inputs) {
        // Values near f32's limit in a valid blob: refused, never non-finite output.
        Err(Error::Overflow) => return Err(Error::Overflow),
        evaluated => evaluated.expect("a valid model evaluates finite inputs from a resident blob"),
    };
    let len = least.saturating_add_signed(inputs.scratch_delta as isize);
    check_streamed(blob, &inputs, &eval, len);
    check_range(&model, probe, &eval);
    let stored = decode(blob).expect("FORMAT.md reads every blob the core accepts");
    reference::assert_matches(&stored, &eval, |_| 0.0);
    if let Some(rig) = model.irradiance_rig() {
        exercise_rig(&model, &rig, probe, &eval);
    }
    exercise_atlas(&model, blob, probe, &eval);
    exercise_proxies(&model, blob, probe, &eval);
    Ok(eval)
}

/// A model's occluder proxies posed by skinning matrices from the probe's rotations (moved by
/// its angles) and subtracted from its shading and transfer at positions and normals from the
/// probe: non-finite skinning, positions or normals are refused with their errors; finite
/// inputs give no NaN, and the streamed model the same bits; a model without proxies refuses
/// with [`Error::NoProxies`].
fn exercise_proxies(model: &Model, blob: &[u8], probe: &Probe, eval: &Evaluation) {
    let info = model.info();
    let a = probe.angles;
    let skinning: Vec<Skinning> = (0..info.bones())
        .map(|b| {
            let r = probe.rotation(b);
            let t = [a[b % 4], a[(b + 1) % 4], a[(b + 2) % 4]];
            [0, 1, 2]
                .map(|i| [r[i][0], r[i][1], r[i][2], t[i]])
                .concat()
                .try_into()
                .expect("twelve values")
        })
        .collect();
    let mut frame = Box::new(ProxyFrame::new());
    let posed = model.pose_proxies(&skinning, &mut frame);
    if !info.has_proxies() {
        assert_eq!(posed, Err(Error::NoProxies));
        return;
    }
    let finite_skinning = skinning.iter().flatten().all(|x| x.is_finite());
    if !finite_skinning {
        assert!(matches!(posed, Err(Error::BadSkinning { .. })));
        return;
    }
    posed.expect("finite skinning poses the proxies");
    let v = info.vertices();
    let positions: Vec<[f32; 3]> = (0..v)
        .map(|j| [a[j % 4], a[(j + 1) % 4], 0.1 * j as f32])
        .collect();
    let normals: Vec<[f32; 3]> = (0..v)
        .map(|j| [a[(j + 2) % 4], 1.0, a[(j + 3) % 4]])
        .collect();
    let lighting = &eval.lighting;
    let mut shading = eval.shading.clone();
    let result = model.occlude(&frame, lighting, &positions, &normals, 0, &mut shading);
    let finite = positions
        .iter()
        .chain(&normals)
        .flatten()
        .all(|x| x.is_finite());
    if !finite {
        assert!(matches!(
            result,
            Err(Error::NonFinitePosition { .. } | Error::NonFiniteNormal { .. })
        ));
        return;
    }
    if !ok_or_overflow(result, "finite inputs occlude") {
        return;
    }
    assert!(shading.iter().all(|x| !x.is_nan()), "NaN occluded shading");
    let mut transfer = eval.transfer.clone();
    let occluded = model.occlude_transfer(
        &frame,
        &eval.rotations,
        &positions,
        &normals,
        0,
        &mut transfer,
    );
    if !ok_or_overflow(occluded, "finite inputs occlude the transfer") {
        return;
    }
    assert!(
        transfer.iter().all(|x| !x.is_nan()),
        "NaN occluded transfer"
    );
    let mut scratch = vec![0u8; info.scratch_bytes()];
    let mut streamed = StreamedModel::open(Streamed::new(blob), &mut scratch).unwrap();
    let mut sframe = Box::new(ProxyFrame::new());
    streamed.pose_proxies(&skinning, &mut sframe).unwrap();
    let mut again = eval.shading.clone();
    streamed
        .occlude(&sframe, lighting, &positions, &normals, 0, &mut again)
        .unwrap();
    let bits = |xs: &[f32]| xs.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&again), bits(&shading), "streamed occlusion differs");
}

/// A model's texel atlas: the streamed reader reads the same atlas, through a buffer of
/// exactly its size and refuses a smaller one; its indices are increasing and below R², its
/// corner UVs (if any) in `[0, 1]` and none past the last triangle; scattering the shading
/// puts row `j` on texel `texel(j)`; the probe's row range and a map of the wrong size are
/// refused with their errors, writing nothing.
fn exercise_atlas(model: &Model, blob: &[u8], probe: &Probe, eval: &Evaluation) {
    let info = model.info();
    let mut least = vec![0u8; info.scratch_bytes()];
    let mut streamed = StreamedModel::open(Streamed::new(blob), &mut least).unwrap();
    let mut buf = vec![0u8; info.texel_atlas_bytes()];
    let read = streamed.texel_atlas(&mut buf).expect("a valid atlas reads");
    assert_eq!(
        read,
        model.texel_atlas(),
        "streamed and resident atlases differ"
    );
    let Some(atlas) = model.texel_atlas() else {
        return;
    };
    let needed = buf.len();
    assert_eq!(
        streamed.texel_atlas(&mut buf[..needed - 1]),
        Err(Error::BufferTooSmall { needed })
    );
    let rows = info.vertices();
    assert_eq!(atlas.rows(), rows);
    let r = atlas.resolution() as usize;
    let texels: Vec<usize> = (0..rows)
        .map(|j| atlas.texel(j).unwrap() as usize)
        .collect();
    assert!(texels.windows(2).all(|w| w[0] < w[1]) && texels[rows - 1] < r * r);
    assert_eq!(
        atlas.texel(rows),
        Err(Error::VertexRange {
            first: rows,
            count: 1
        })
    );
    let triangles = atlas.triangles();
    for t in 0..triangles {
        let uvs = atlas.corner_uvs(t).unwrap();
        assert!(uvs.as_flattened().iter().all(|x| (0.0..=1.0).contains(x)));
    }
    assert_eq!(
        atlas.corner_uvs(triangles),
        Err(Error::TriangleRange {
            triangle: triangles,
            triangles
        })
    );
    let shaded: Vec<[f32; 3]> = eval.shading.iter().map(|&s| [s, -s, 1.0]).collect();
    let mut map = vec![[f32::NAN; 3]; r * r];
    atlas.scatter(0, &shaded, &mut map).unwrap();
    for (t, texel) in map.iter().enumerate() {
        match texels.binary_search(&t) {
            Ok(j) => assert_eq!(texel, &shaded[j]),
            Err(_) => assert!(texel[0].is_nan(), "texel {t} of no row written"),
        }
    }
    let first = probe.first as usize % (rows + 9);
    let count = probe.count as usize % (rows + 9);
    let chunk = vec![[0.0f32; 3]; count];
    let before = map.clone();
    match first + count <= rows {
        true => atlas.scatter(first, &chunk, &mut map).unwrap(),
        false => assert_eq!(
            atlas.scatter(first, &chunk, &mut map),
            Err(Error::VertexRange { first, count })
        ),
    }
    assert!(matches!(
        atlas.scatter(0, &shaded, &mut map[1..]),
        Err(Error::WrongLength {
            what: Input::AtlasMap,
            ..
        })
    ));
    let written = (first + count <= rows) as usize * count;
    let bits = |t: &[f32; 3]| t.map(f32::to_bits);
    let changed = map
        .iter()
        .zip(&before)
        .filter(|(a, b)| bits(a) != bits(b))
        .count();
    assert!(
        changed <= written,
        "{changed} texels changed by {written} rows"
    );
}

/// A model's irradiance rig lit by a sphere and a point light placed from the probe: lights
/// the core refuses are refused with [`Error::BadLight`]; valid ones give finite rig vectors
/// and finite rig-lit and per-vertex shading at finite positions, or a refusal of a position
/// that is not finite, never a panic.
fn exercise_rig(model: &Model, rig: &IrradianceRig<'_>, probe: &Probe, eval: &Evaluation) {
    let a = probe.angles;
    let lights = [
        Light::Sphere(SphereLight {
            position: [a[0], a[1], a[2]],
            radius: probe.lighting[0].abs(),
            radiance: [probe.lighting[1]; 3],
        }),
        Light::Point(PointLight {
            position: [a[3], a[0], a[1]],
            intensity: [probe.lighting[2].abs(); 3],
        }),
    ];
    let info = model.info();
    let mut vectors = vec![[0.0f32; 3]; rig.vectors() * info.coeffs()];
    let place = Placement::IDENTITY;
    let valid = lights.iter().all(|l| l.validate().is_ok());
    match rig.vectors_from_lights(info.order(), &place, &lights, &[], &mut vectors) {
        Err(Error::BadLight { .. }) if !valid => return,
        Err(e) => panic!("rig vectors of valid lights refused: {e}"),
        Ok(()) => assert!(valid, "invalid lights accepted"),
    }
    let positions: Vec<[f32; 3]> = (0..info.vertices())
        .map(|j| [a[j % 4], a[(j + 1) % 4], a[(j + 2) % 4]])
        .collect();
    let mut pose = Box::new(PoseWeights::new());
    model
        .set_pose(&eval.angles, &mut pose)
        .expect("set once already");
    let mut buffer = vec![0.0f32; info.rig_lit_weights_len(rig.vectors())];
    let mut lit = RigLitWeights::new(&mut buffer);
    let lit_ok = model.light_rig(&pose, &vectors, &eval.rotations, &mut lit);
    if vectors.iter().flatten().any(|x| !x.is_finite()) {
        assert!(lit_ok.is_err(), "non-finite rig vectors accepted");
        return;
    }
    if !ok_or_overflow(lit_ok, "finite rig vectors light a valid model") {
        return;
    }
    let mut out = vec![[0.0f32; 3]; info.vertices()];
    let finite = positions.iter().flatten().all(|x| x.is_finite());
    let shaded = model.shade_rig(&lit, rig, &place, &positions, 0, &mut out);
    let weights = [0.5f32; 2];
    let near = model.shade_lights(
        &pose,
        &eval.rotations,
        &lights,
        &weights,
        &positions,
        0,
        &mut out,
    );
    if finite {
        let shaded = ok_or_overflow(shaded, "finite positions shade");
        if !(ok_or_overflow(near, "finite positions shade per vertex") && shaded) {
            return;
        }
        assert!(out.iter().flatten().all(|x| !x.is_nan()), "NaN shading");
    } else {
        assert!(matches!(shaded, Err(Error::NonFinitePosition { .. })));
        assert!(matches!(near, Err(Error::NonFinitePosition { .. })));
    }
}

fn angles(info: &ModelInfo, probe: &Probe) -> Vec<f32> {
    (0..info.pose_len()).map(|j| probe.angles[j % 4]).collect()
}

fn lighting(info: &ModelInfo, probe: &Probe) -> Vec<f32> {
    (0..info.coeffs()).map(|c| probe.lighting[c % 4]).collect()
}

fn rotations(info: &ModelInfo, probe: &Probe) -> Vec<Rotation> {
    (0..info.bones()).map(|b| probe.rotation(b)).collect()
}

/// A pose set and lit from a probe's inputs.
struct Lit {
    angles: Vec<f32>,
    lighting: Vec<f32>,
    rotations: Vec<Rotation>,
    pose: Box<PoseWeights>,
    lit: Box<LitWeights>,
}

fn set_and_light(model: &mut impl Eval, probe: &Probe) -> Result<Lit, Error> {
    let info = *model.info();
    let (angles, lighting, rotations) = (
        angles(&info, probe),
        lighting(&info, probe),
        rotations(&info, probe),
    );
    let mut pose = Box::new(PoseWeights::new());
    model.set_pose(&angles, &mut pose)?;
    let mut lit = Box::new(LitWeights::new());
    model.light(&pose, &lighting, &rotations, &mut lit)?;
    Ok(Lit {
        angles,
        lighting,
        rotations,
        pose,
        lit,
    })
}

/// Sets the pose, lights it and evaluates every vertex.
fn evaluate(model: &mut impl Eval, probe: &Probe) -> Result<Evaluation, Error> {
    let l = set_and_light(model, probe)?;
    let v = model.info().vertices();
    let mut transfer = vec![0.0f32; v * l.lighting.len()];
    model.transfer(&l.pose, 0, &mut transfer)?;
    let mut shading = vec![0.0f32; v];
    model.shade(&l.lit, 0, &mut shading)?;
    let mut bones = vec![0u16; v];
    model.vertex_bones(0, &mut bones)?;
    Ok(Evaluation {
        angles: l.angles,
        lighting: l.lighting,
        rotations: l.rotations,
        transfer,
        shading,
        bones,
        encoding: model.info().encoding(),
    })
}

/// Raw probe inputs: non-finite values, wrong lengths, skewed rotations and weights that were
/// never set each get their own error, and never a panic.
fn check_refusals(model: &Model, probe: &Probe) {
    let info = *model.info();
    let (angles, lighting, rotations) = (
        angles(&info, probe),
        lighting(&info, probe),
        rotations(&info, probe),
    );
    let first_bad = |xs: &[f32]| xs.iter().position(|x| !x.is_finite());
    let mut pose = Box::new(PoseWeights::new());
    let a = angles.len();
    assert_eq!(
        model.set_pose(&angles[..a - 1], &mut pose),
        Err(Error::WrongLength {
            what: Input::Angles,
            expected: a,
            found: a - 1
        })
    );
    let mut lit = Box::new(LitWeights::new());
    assert_eq!(
        model.light(&pose, &lighting, &rotations, &mut lit),
        Err(Error::WeightsNotSet),
        "lighting before any pose"
    );
    let set = model.set_pose(&angles, &mut pose);
    if let Some(index) = first_bad(&angles) {
        assert_eq!(set, Err(Error::NonFiniteAngle { index }));
        return;
    }
    if !ok_or_overflow(set, "finite angles set a pose") {
        return;
    }
    // The first bone whose matrix is not a rotation: all of them when skewed, else the first
    // whose turn overflowed.
    let bad_bone = match probe.skew {
        true if !rotations.is_empty() => Some(0),
        _ => rotations
            .iter()
            .position(|r| first_bad(r.as_flattened()).is_some()),
    };
    if let Frame::Bones { .. } = info.frame() {
        assert_eq!(
            model.light(&pose, &lighting, &rotations[1..], &mut lit),
            Err(Error::WrongLength {
                what: Input::BoneRotations,
                expected: rotations.len(),
                found: rotations.len() - 1
            })
        );
    }
    let lit_result = model.light(&pose, &lighting, &rotations, &mut lit);
    if let Some(index) = first_bad(&lighting) {
        assert_eq!(lit_result, Err(Error::NonFiniteLighting { index }));
        return;
    }
    if let Some(bone) = bad_bone {
        assert_eq!(lit_result, Err(Error::BadRotation { bone }));
        assert_eq!(
            model.shade(&lit, 0, &mut [0.0; 1]),
            Err(Error::WeightsNotSet),
            "shading with the weights of a failed light"
        );
        return;
    }
    if !ok_or_overflow(lit_result, "finite lighting lights a pose") {
        return;
    }
    if info.frame() == Frame::World {
        // A world-frame model ignores bone rotations, however many.
        let mut ignoring = Box::new(LitWeights::new());
        let skeleton = [[[2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]; 3];
        model
            .light(&pose, &lighting, &skeleton, &mut ignoring)
            .unwrap();
        let shade = |lit: &LitWeights| {
            let mut out = vec![0.0f32; info.vertices()];
            let shaded = model.shade(lit, 0, &mut out);
            (shaded, out.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
        };
        assert!(
            shade(&ignoring) == shade(&lit),
            "bone rotations changed a world-frame model"
        );
    }
    let n2 = lighting.len();
    if n2 > 1 {
        assert!(matches!(
            model.transfer(&pose, 0, &mut [0.0; 1]),
            Err(Error::WrongLength {
                what: Input::Transfer,
                ..
            })
        ));
    }
}

/// Streamed evaluation with `len` bytes of scratch: bit-identical to resident evaluation when
/// the model opens, which it must when the scratch holds `ModelInfo::scratch_bytes`.
fn check_streamed(blob: &[u8], inputs: &Probe, resident: &Evaluation, len: usize) {
    let mut scratch = vec![0u8; len];
    let least = Model::parse(blob).unwrap().info().scratch_bytes();
    match StreamedModel::open(Streamed::new(blob), &mut scratch) {
        Ok(mut model) => {
            let streamed = evaluate(&mut model, inputs).expect("streamed evaluation");
            assert!(
                bits(&streamed) == bits(resident),
                "streamed evaluation with {len} bytes of scratch differs"
            );
        }
        Err(Error::BufferTooSmall { needed }) => assert!(
            len < least && needed == least,
            "scratch of {len} bytes refused (least {least}, needed {needed})"
        ),
        Err(e) => panic!("streamed opening failed: {e:?}"),
    }
}

/// `true` for `Ok`, `false` for [`Error::Overflow`] (a valid blob's values, with finite
/// inputs, beyond f32: the caller stops checking what depends on the result); any other
/// error panics with `what` was expected.
fn ok_or_overflow(result: Result<(), Error>, what: &str) -> bool {
    match result {
        Ok(()) => true,
        Err(Error::Overflow) => false,
        Err(e) => panic!("{what}: {e}"),
    }
}

/// `check_streamed` for every scratch length in `lens`, against one resident evaluation of
/// the valid blob `blob` at the probe's inputs made finite.
pub fn check_streaming(blob: &[u8], probe: &Probe, lens: impl IntoIterator<Item = usize>) {
    let mut model = Model::parse(blob).expect("a valid blob");
    let inputs = probe.sanitised();
    let resident = match evaluate(&mut model, &inputs) {
        Err(Error::Overflow) => return,
        evaluated => evaluated.unwrap(),
    };
    for len in lens {
        check_streamed(blob, &inputs, &resident, len);
    }
}

/// The evaluation's numbers as bits, so NaN compares equal to itself and -0 differs from +0.
fn bits(e: &Evaluation) -> (Vec<u32>, Vec<u32>, &[u16]) {
    let b = |xs: &[f32]| xs.iter().map(|x| x.to_bits()).collect();
    (b(&e.transfer), b(&e.shading), &e.bones)
}

/// The probe's vertex range: the matching slice of the whole when inside the model, a
/// `VertexRange` error otherwise, for shading, transfer and bone indices alike.
fn check_range(model: &Model, probe: &Probe, whole: &Evaluation) {
    let v = model.info().vertices();
    let first = if probe.far {
        usize::MAX - probe.first as usize % 8
    } else {
        probe.first as usize % (v + 9)
    };
    let count = probe.count as usize % (v + 9);
    let inside = first.checked_add(count).is_some_and(|end| end <= v);
    let n2 = model.info().coeffs();
    let Lit { pose, lit, .. } = match set_and_light(&mut { *model }, &probe.sanitised()) {
        Err(Error::Overflow) => return,
        lit => lit.unwrap(),
    };
    let refused = Err(Error::VertexRange { first, count });
    let (mut shading, mut transfer, mut bones) = (
        vec![0.0f32; count],
        vec![0.0f32; count * n2],
        vec![0u16; count],
    );
    let results = [
        model.shade(&lit, first, &mut shading),
        model.transfer(&pose, first, &mut transfer),
        model.vertex_bones(first, &mut bones),
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
