//! Irradiance rigs in the core: the section's bytes round-trip and refuse what is malformed,
//! and rig-lit shading equals each vertex's transfer dotted with the rig's lighting at its
//! position (the definition), for world- and bone-frame models, resident and streamed.

use aprt_core::{
    AxisKind, Error, IrradianceRig, LitWeights, Model, Placement, PoseWeights, RigLayout,
    RigLitWeights, RigShape, StreamedModel,
};
use aprt_tests::{axis_angle, noise, random_model};
use aprt_trainer::{BoneFrames, Precision, encode_model_with_rig};

/// The rig's bytes for `shape` with a random matrix over `n` random samples.
fn rig_bytes(shape: RigShape, n: usize, seed: u64) -> Vec<u8> {
    let samples: Vec<[f32; 3]> = noise(seed, 3 * n)
        .chunks_exact(3)
        .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32])
        .collect();
    let matrix: Vec<f32> = noise(seed + 1, shape.vectors() * n)
        .iter()
        .map(|&x| x as f32)
        .collect();
    let layout = RigLayout {
        shape,
        centre: [0.1, -0.2, 0.3],
        half: [1.5, 0.6, 0.4],
        radius: 1.7,
        table: &[[1.0, 40.0], [2.0, 9.0], [4.0, 2.0]],
        samples: &samples,
        matrix: &matrix,
    };
    let mut bytes = vec![0u8; layout.len()];
    assert_eq!(layout.write(&mut bytes), Ok(bytes.len()));
    bytes
}

const SHAPES: [RigShape; 3] = [
    RigShape::Gradient,
    RigShape::Product([AxisKind::Lattice(3), AxisKind::Linear, AxisKind::Constant]),
    RigShape::Product([
        AxisKind::Lattice(4),
        AxisKind::Lattice(2),
        AxisKind::Lattice(2),
    ]),
];

#[test]
fn rig_bytes_round_trip() {
    for shape in SHAPES {
        let bytes = rig_bytes(shape, 9, 5);
        let rig = IrradianceRig::parse(&bytes).unwrap();
        assert_eq!(rig.shape(), shape);
        assert_eq!((rig.samples(), rig.vectors()), (9, shape.vectors()));
        assert_eq!(rig.table_entry(1), [2.0, 9.0]);
        assert_eq!(rig.radius(), 1.7);
    }
}

#[test]
fn malformed_rigs_are_refused_without_panic() {
    let good = rig_bytes(SHAPES[1], 7, 9);
    // Every truncation, and every single-byte change of the prelude.
    for len in 0..good.len() {
        assert!(IrradianceRig::parse(&good[..len]).is_err(), "length {len}");
    }
    for at in 0..44 {
        for value in [0u8, 1, 2, 17, 0x7f, 0xff] {
            let mut bad = good.clone();
            bad[at] = value;
            let _ = IrradianceRig::parse(&bad);
        }
    }
    let with = |at: usize, value: f32| {
        let mut bad = good.clone();
        bad[at..at + 4].copy_from_slice(&value.to_le_bytes());
        IrradianceRig::parse(&bad).err()
    };
    let bad = Some(Error::BadIrradianceRig);
    assert_eq!(with(28, 0.0), bad, "a flat box");
    assert_eq!(with(40, -1.0), bad, "a negative radius");
    assert_eq!(with(52, 0.5), bad, "a table whose distances decrease");
    assert_eq!(with(56, -1.0), bad, "a negative error");
    assert_eq!(with(good.len() - 4, f32::NAN), bad, "NaN in the matrix");
    let mut wrong_k = good.clone();
    wrong_k[8] = 5;
    assert_eq!(
        IrradianceRig::parse(&wrong_k).err(),
        bad,
        "K not the shape's"
    );
    let mut long = good.clone();
    long.extend_from_slice(&[0; 4]);
    assert_eq!(IrradianceRig::parse(&long).err(), bad, "trailing bytes");
}

/// Rig-lit shading against its definition: for every vertex, its transfer (in its bone's
/// frame) dotted with the rig's world lighting at its position rotated into that frame. The
/// reference rotates the vertex's transfer to the world instead, through a second model lit
/// per vertex: `shade` of a single-vector rig at that vertex.
#[test]
fn rig_shading_is_transfer_dot_rig_lighting() {
    let (order, vertices) = (3, 37);
    for bones in [None, Some(3)] {
        let mut model = random_model(order, vertices, 4, 2, Some(5));
        if let Some(count) = bones {
            model.bones = Some(BoneFrames {
                count,
                vertex_bone: (0..vertices)
                    .map(|j| (j * count / vertices) as u16)
                    .collect(),
            });
        }
        let rotations = [
            axis_angle([1.0, 2.0, 0.5], 0.7),
            axis_angle([0.0, 0.0, 1.0], -1.2),
            axis_angle([-1.0, 0.3, 0.2], 2.5),
        ];
        let rotations = &rotations[..bones.unwrap_or(0)];
        for shape in SHAPES {
            let rig_blob = rig_bytes(shape, 11, 21);
            let blob = encode_model_with_rig(&model, Precision::F32, Some(&rig_blob)).unwrap();
            let core = Model::parse(&blob).unwrap();
            let rig = core.irradiance_rig().expect("the model carries its rig");
            let n2 = order * order;
            let vectors: Vec<[f32; 3]> = noise(31, 3 * rig.vectors() * n2)
                .chunks_exact(3)
                .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
                .collect();
            let placement = Placement {
                rotation: axis_angle([0.2, 1.0, 0.1], 0.4),
                translation: [0.5, -1.0, 2.0],
            };
            let positions: Vec<[f32; 3]> = noise(41, 3 * vertices)
                .chunks_exact(3)
                .map(|p| placement.to_world([2.0 * p[0] as f32, p[1] as f32, p[2] as f32]))
                .collect();
            let mut pose = PoseWeights::new();
            core.set_pose(&[0.3, -0.1, 0.2, 0.5], &mut pose).unwrap();
            let mut buffer = vec![0.0; core.info().rig_lit_weights_len(rig.vectors())];
            let mut lit = RigLitWeights::new(&mut buffer);
            core.light_rig(&pose, &vectors, rotations, &mut lit)
                .unwrap();
            let mut shaded = vec![[0.0; 3]; vertices];
            core.shade_rig(&lit, &rig, &placement, &positions, 0, &mut shaded)
                .unwrap();

            // Reference: per vertex, the rig's lighting there, through the plain `light` and
            // `shade` calls one channel at a time.
            let mut here = vec![[0.0f32; 3]; n2];
            let mut single = LitWeights::new();
            let mut one = [0.0f32; 1];
            for (j, p) in positions.iter().enumerate() {
                rig.lighting_at(&vectors, &placement, *p, &mut here);
                for ch in 0..3 {
                    let channel: Vec<f32> = here.iter().map(|c| c[ch]).collect();
                    core.light(&pose, &channel, rotations, &mut single).unwrap();
                    core.shade(&single, j, &mut one).unwrap();
                    let (got, want) = (shaded[j][ch], one[0]);
                    assert!(
                        (got - want).abs() <= 1e-4 * (1.0 + want.abs()),
                        "{shape:?}, bones {bones:?}, vertex {j}, channel {ch}: {got} vs {want}"
                    );
                }
            }

            // The streamed model reads the rig and shades alike, over a partial range.
            let mut scratch = vec![0u8; core.info().scratch_bytes()];
            let mut streamed = StreamedModel::open(&blob[..], &mut scratch).unwrap();
            let mut rig_buf = vec![0u8; streamed.info().irradiance_rig_bytes()];
            let streamed_rig = streamed.irradiance_rig(&mut rig_buf).unwrap();
            assert_eq!(streamed_rig, rig);
            let mut part = vec![[0.0; 3]; 12];
            streamed
                .shade_rig(
                    &lit,
                    &streamed_rig,
                    &placement,
                    &positions[5..17],
                    5,
                    &mut part,
                )
                .unwrap();
            assert_eq!(part, shaded[5..17]);
        }
    }
}

#[test]
fn rig_calls_refuse_bad_inputs() {
    let model = random_model(2, 16, 3, 1, Some(3));
    let rig_blob = rig_bytes(RigShape::Gradient, 5, 3);
    let blob = encode_model_with_rig(&model, Precision::F32, Some(&rig_blob)).unwrap();
    let core = Model::parse(&blob).unwrap();
    let rig = core.irradiance_rig().unwrap();
    let mut pose = PoseWeights::new();
    core.set_pose(&[0.0; 3], &mut pose).unwrap();
    let mut buffer = vec![0.0; core.info().rig_lit_weights_len(4)];
    let mut lit = RigLitWeights::new(&mut buffer);
    let mut vectors = vec![[1.0f32; 3]; 4 * 4];
    assert!(matches!(
        core.light_rig(&pose, &vectors[..7], &[], &mut lit),
        Err(Error::WrongLength { .. })
    ));
    vectors[3][1] = f32::NAN;
    assert_eq!(
        core.light_rig(&pose, &vectors, &[], &mut lit),
        Err(Error::NonFiniteLighting { index: 3 })
    );
    vectors[3][1] = 0.0;
    let mut out = vec![[0.0; 3]; 16];
    let positions = vec![[0.0f32; 3]; 16];
    let place = Placement::IDENTITY;
    assert_eq!(
        core.shade_rig(&lit, &rig, &place, &positions, 0, &mut out),
        Err(Error::WeightsNotSet)
    );
    core.light_rig(&pose, &vectors, &[], &mut lit).unwrap();
    let mut nan = positions.clone();
    nan[2][0] = f32::INFINITY;
    assert_eq!(
        core.shade_rig(&lit, &rig, &place, &nan, 0, &mut out),
        Err(Error::NonFinitePosition { index: 2 })
    );
    assert!(matches!(
        core.shade_rig(&lit, &rig, &place, &positions[..3], 0, &mut out),
        Err(Error::WrongLength { .. })
    ));
    let other = rig_bytes(SHAPES[1], 5, 3);
    let other = IrradianceRig::parse(&other).unwrap();
    assert_eq!(
        core.shade_rig(&lit, &other, &place, &positions, 0, &mut out),
        Err(Error::WeightsForOtherRig)
    );
    let mut small = vec![0.0; 10];
    assert!(matches!(
        core.light_rig(&pose, &vectors, &[], &mut RigLitWeights::new(&mut small)),
        Err(Error::WeightsTooSmall { .. })
    ));
}

/// Old readers skip the section; a model without a rig says so when streamed.
#[test]
fn a_model_without_a_rig_has_none() {
    let model = random_model(2, 8, 3, 1, Some(2));
    let blob = aprt_trainer::encode_model(&model, Precision::F32).unwrap();
    let core = Model::parse(&blob).unwrap();
    assert!(core.irradiance_rig().is_none());
    let mut scratch = vec![0u8; core.info().scratch_bytes()];
    let mut streamed = StreamedModel::open(&blob[..], &mut scratch).unwrap();
    assert_eq!(streamed.info().irradiance_rig_bytes(), 0);
    assert_eq!(
        streamed.irradiance_rig(&mut [0u8; 64]).err(),
        Some(Error::NoIrradianceRig)
    );
}

/// The per-frame call an engine makes, against the same projection written out by hand.
#[test]
fn vectors_from_lights_project_every_light_at_every_sample() {
    use aprt_core::{Light, PointLight, SphereLight};
    let bytes = rig_bytes(SHAPES[1], 9, 13);
    let rig = IrradianceRig::parse(&bytes).unwrap();
    let lights = [
        Light::Sphere(SphereLight {
            position: [0.5, 2.0, -1.0],
            radius: 0.3,
            radiance: [2.0, 1.0, 0.5],
        }),
        Light::Point(PointLight {
            position: [-3.0, 0.1, 0.2],
            intensity: [1.0, 2.0, 3.0],
        }),
    ];
    let sky = [
        [0.3f32, 0.2, 0.1],
        [0.0, 0.05, 0.0],
        [0.01, 0.0, 0.0],
        [0.0, 0.0, 0.02],
    ];
    let place = Placement {
        rotation: axis_angle([0.3, 0.1, 1.0], 0.8),
        translation: [0.2, 0.0, -0.5],
    };
    let mut got = vec![[0.0f32; 3]; rig.vectors() * 4];
    rig.vectors_from_lights(2, &place, &lights, &sky, &mut got)
        .unwrap();
    let mut want = vec![[0.0f32; 3]; rig.vectors() * 4];
    let mut scratch = [[0.0f32; 3]; 4];
    rig.vectors_from(
        4,
        &place,
        &mut scratch,
        |p, l| {
            l.copy_from_slice(&sky);
            for light in &lights {
                light.add_radiance_sh(2, p, l).unwrap();
            }
        },
        &mut want,
    )
    .unwrap();
    assert_eq!(got, want);
    let bad = [Light::Point(PointLight {
        position: [f32::NAN, 0.0, 0.0],
        intensity: [1.0; 3],
    })];
    assert!(matches!(
        rig.vectors_from_lights(2, &place, &bad, &[], &mut got),
        Err(Error::BadLight { index: 0, .. })
    ));
    assert!(matches!(
        rig.vectors_from_lights(2, &place, &lights, &sky[..3], &mut got),
        Err(Error::WrongLength { .. })
    ));
}
