//! The occluder proxies through the C ABI: the proxy frame's storage and tag checks, NULL and
//! misaligned pointers of every proxies call, a skinning of the wrong length, proxies posed by
//! another model, a model without proxies, occlusion before posing; and on both models with
//! proxies (the golden one and the fuzz seed), resident, streamed and the core called from
//! Rust agree bit for bit, over the whole mesh and over a sub-range.

use crate::common;

use std::ffi::c_void;
use std::ptr::{null, null_mut};

use aprt_capi::frame::*;
use aprt_capi::lights::aprt_project_directional;
use aprt_capi::model::*;
use aprt_capi::proxies::*;
use aprt_capi::*;
use aprt_core::{LitWeights, Model, PoseWeights, ProxyFrame, Rotation, Skinning};
use common::*;

use aprt_status::{BadHandle, Misaligned, NoProxies, NullPointer, Ok as OK, WrongLength};

/// The fuzz seed with occluder proxies, its 48-byte probe prefix stripped.
fn seed_blob() -> Vec<u8> {
    std::fs::read(repo().join("fuzz/corpus/reader/seed-proxies-bones-f32")).unwrap()[48..].to_vec()
}

const IDENTITY: Rotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
const TURN: Rotation = [[0.8, -0.6, 0.0], [0.6, 0.8, 0.0], [0.0, 0.0, 1.0]];
const SHIFT: [f32; 3] = [0.05, -0.1, 0.2];
const POSITIONS: [[f32; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [0.5, 0.1, 0.2],
    [-0.3, 0.4, 0.1],
    [0.2, -0.5, 0.6],
];
const NORMALS: [[f32; 3]; 4] = [
    [0.0, 0.0, 1.0],
    [0.6, 0.0, 0.8],
    [0.0, -0.6, 0.8],
    [0.0, 0.0, 0.0],
];

/// A model handle (resident, or streamed through its own memory and scratch) with what the
/// calls need, sized by its info.
struct Subject {
    _mem: Vec<Block>,
    _memory: Box<Memory>,
    _scratch: Vec<u8>,
    model: *mut aprt_model,
    info: aprt_model_info,
    /// Per bone, 9 floats: the rotation (IDENTITY on even bones, TURN on odd ones).
    bones: Vec<f32>,
    /// Per bone, 12 floats: the rotation with SHIFT as its translation.
    skinning: Vec<f32>,
    sky: Vec<f32>,
    positions: Vec<f32>,
    normals: Vec<f32>,
}

fn rotation(b: usize) -> Rotation {
    if b % 2 == 1 { TURN } else { IDENTITY }
}

fn subject(blob: &[u8], streamed: bool) -> Subject {
    let mut mem = storage(aprt_model_size());
    let mut memory = Box::new(Memory::new(blob.to_vec()));
    let mut scratch = Vec::new();
    let model = match streamed {
        false => {
            let mut model = null_mut();
            let len = aprt_model_size();
            let status = aprt_model_init(blob.as_ptr(), blob.len(), ptr(&mut mem), len, &mut model);
            assert_eq!(status, OK);
            model
        }
        true => {
            let (status, model) = stream(&mut memory, &mut scratch, &mut mem);
            assert_eq!(status, OK);
            model
        }
    };
    let mut info = aprt_model_info::default();
    assert_eq!(aprt_model_get_info(model, &mut info), OK);
    let (n, bones) = (info.vertices as usize, info.bones as usize);
    let mut sky = vec![0.0f32; 36];
    let dir = [0.5f32, -0.8, 0.9];
    let status = aprt_project_directional(info.order, dir.as_ptr(), 3.0, sky.as_mut_ptr(), 36);
    assert_eq!(status, OK);
    sky.truncate(info.coeffs as usize);
    let skinning = (0..bones)
        .flat_map(|b| {
            let r = rotation(b);
            (0..3).flat_map(move |i| [r[i][0], r[i][1], r[i][2], SHIFT[i]])
        })
        .collect();
    Subject {
        _mem: mem,
        _memory: memory,
        _scratch: scratch,
        model,
        info,
        bones: (0..bones).flat_map(|b| rotation(b).concat()).collect(),
        skinning,
        sky,
        positions: (0..n).flat_map(|j| POSITIONS[j % 4]).collect(),
        normals: (0..n).flat_map(|j| NORMALS[j % 4]).collect(),
    }
}

/// A proxy frame in its own storage.
struct Proxies {
    _mem: Vec<Block>,
    frame: *mut aprt_proxy_frame,
}

fn proxies() -> Proxies {
    let mut mem = storage(aprt_proxy_frame_size());
    let mut frame = null_mut();
    let len = aprt_proxy_frame_size();
    assert_eq!(aprt_proxy_frame_init(ptr(&mut mem), len, &mut frame), OK);
    Proxies { _mem: mem, frame }
}

impl Subject {
    fn n(&self) -> usize {
        self.info.vertices as usize
    }

    fn n2(&self) -> usize {
        self.info.coeffs as usize
    }

    fn pose(&self, p: &Proxies) -> aprt_status {
        let s = &self.skinning;
        aprt_pose_proxies(self.model, s.as_ptr(), s.len(), p.frame)
    }

    /// `aprt_occlude` of vertices `first .. first + out.len()`.
    fn occlude(&self, p: &Proxies, first: usize, out: &mut [f32]) -> aprt_status {
        let range = 3 * first..3 * (first + out.len());
        aprt_occlude(
            self.model,
            p.frame,
            self.sky.as_ptr(),
            self.sky.len(),
            self.positions[range.clone()].as_ptr(),
            self.normals[range].as_ptr(),
            first,
            out.as_mut_ptr(),
            out.len(),
        )
    }

    /// `aprt_occlude_transfer` of vertices `first ..` (n² floats each in `out`).
    fn occlude_transfer(&self, p: &Proxies, first: usize, out: &mut [f32]) -> aprt_status {
        let count = out.len() / self.n2();
        let range = 3 * first..3 * (first + count);
        aprt_occlude_transfer(
            self.model,
            p.frame,
            self.bones.as_ptr(),
            self.info.bones as usize,
            self.positions[range.clone()].as_ptr(),
            self.normals[range].as_ptr(),
            first,
            count,
            out.as_mut_ptr(),
            out.len(),
        )
    }

    /// Shading and transfer of the frame (the pose vector all 0.1), occluded by posed proxies.
    fn occluded(&self) -> (Vec<f32>, Vec<f32>) {
        let (n, n2) = (self.n(), self.n2());
        let mut frame_mem = storage(aprt_frame_size());
        let mut frame = null_mut();
        let len = aprt_frame_size();
        assert_eq!(aprt_frame_init(ptr(&mut frame_mem), len, &mut frame), OK);
        let angles = vec![0.1f32; self.info.pose_len as usize];
        let (b, nb) = (self.bones.as_ptr(), self.info.bones as usize);
        assert_eq!(
            aprt_set_pose(self.model, frame, angles.as_ptr(), angles.len()),
            OK
        );
        let status = aprt_light_sh(self.model, frame, self.sky.as_ptr(), n2, b, nb);
        assert_eq!(status, OK);
        let (mut shading, mut transfer) = (vec![0.0f32; n], vec![0.0f32; n * n2]);
        assert_eq!(
            aprt_shade(self.model, frame, 0, shading.as_mut_ptr(), n),
            OK
        );
        let (t, tl) = (transfer.as_mut_ptr(), transfer.len());
        assert_eq!(aprt_transfer(self.model, frame, 0, t, tl), OK);
        let p = proxies();
        assert_eq!(self.pose(&p), OK);
        assert_eq!(self.occlude(&p, 0, &mut shading), OK);
        assert_eq!(self.occlude_transfer(&p, 0, &mut transfer), OK);
        (shading, transfer)
    }
}

fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn the_info_says_which_models_have_proxies() {
    for (kind, has) in [
        ("atlas", false),
        ("bones", false),
        ("world", false),
        ("proxies", true),
    ] {
        let s = subject(&golden(kind), false);
        assert_eq!(s.info.has_proxies, has, "{kind}");
    }
    assert!(subject(&seed_blob(), true).info.has_proxies);
    assert!(!subject(&rig_blob(), false).info.has_proxies);
    // The new field sits in what was padding: the other fields keep their offsets.
    use std::mem::offset_of;
    let after_bools = 35usize.next_multiple_of(align_of::<usize>());
    assert_eq!(offset_of!(aprt_model_info, streamed), 34);
    assert_eq!(offset_of!(aprt_model_info, has_proxies), 35);
    assert_eq!(offset_of!(aprt_model_info, scratch_bytes), after_bools);
    let size = after_bools + 2 * size_of::<usize>();
    assert_eq!(size_of::<aprt_model_info>(), size);
}

#[test]
fn the_proxy_frame_storage_and_tag_are_checked() {
    let (size, align) = (aprt_proxy_frame_size(), aprt_proxy_frame_align());
    assert!((2048..8192).contains(&size), "about 3 KiB: {size}");
    assert!((8..=64).contains(&align) && size.is_multiple_of(align));
    let mut mem = storage(size + 64);
    let base = ptr(&mut mem).cast::<u8>();
    let mut frame = null_mut();
    assert_eq!(
        aprt_proxy_frame_init(null_mut(), size, &mut frame),
        NullPointer
    );
    assert_eq!(
        aprt_proxy_frame_init(base.cast(), size, null_mut()),
        NullPointer
    );
    let odd = base.wrapping_add(4).cast::<c_void>();
    assert_eq!(aprt_proxy_frame_init(odd, size, &mut frame), Misaligned);
    assert!(frame.is_null(), "a refused init leaves *out NULL");
    let status = aprt_proxy_frame_init(base.cast(), size - 1, &mut frame);
    assert_eq!(status, aprt_status::StorageTooSmall);
    assert_eq!(aprt_proxy_frame_init(base.cast(), size, &mut frame), OK);
    assert_eq!(frame.cast::<u8>(), base);

    let s = subject(&golden("proxies"), false);
    let (sk, skl) = (s.skinning.as_ptr(), s.skinning.len());
    assert_eq!(aprt_pose_proxies(s.model, sk, skl, frame), OK);
    // The tag is the first 8 bytes: without them the storage is no proxy frame.
    let mut tag = [0u8; 8];
    swap_first_bytes(base, &mut tag);
    assert_ne!(tag, [0; 8]);
    assert_eq!(aprt_pose_proxies(s.model, sk, skl, frame), BadHandle);
    swap_first_bytes(base, &mut tag);
    assert_eq!(aprt_pose_proxies(s.model, sk, skl, frame), OK);

    // Zeroed storage, a frame, a model: none is a proxy frame (each is at least 8 bytes, so
    // the check reads inside it). A proxy frame is no model either (a model is smaller, so its
    // tag's offset lies inside the proxy frame).
    let zeroed = storage(size);
    let zeroed = zeroed.as_ptr().cast_mut().cast::<aprt_proxy_frame>();
    assert_eq!(aprt_pose_proxies(s.model, sk, skl, zeroed), BadHandle);
    let mut frame_mem = storage(aprt_frame_size());
    let mut other = null_mut();
    let len = aprt_frame_size();
    assert_eq!(aprt_frame_init(ptr(&mut frame_mem), len, &mut other), OK);
    assert_eq!(aprt_pose_proxies(s.model, sk, skl, other.cast()), BadHandle);
    assert_eq!(
        aprt_pose_proxies(s.model, sk, skl, s.model.cast()),
        BadHandle
    );
    assert!(aprt_model_size() <= size);
    assert_eq!(aprt_pose_proxies(frame.cast(), sk, skl, frame), BadHandle);

    // Re-initialising empties it.
    assert_eq!(aprt_proxy_frame_init(base.cast(), size, &mut frame), OK);
    let p = Proxies {
        _mem: Vec::new(),
        frame,
    };
    let mut out = vec![0.0f32; 4];
    assert_eq!(s.occlude(&p, 0, &mut out), aprt_status::WeightsNotSet);
}

/// Swaps the first 8 bytes at `base` with `bytes`.
#[allow(unsafe_code)]
fn swap_first_bytes(base: *mut u8, bytes: &mut [u8; 8]) {
    // SAFETY: `base` is the start of the test's handle storage (at least 8 bytes), which no
    // reference borrows during the call.
    unsafe { std::ptr::swap_nonoverlapping(base, bytes.as_mut_ptr(), 8) };
}

#[test]
fn null_pointers_are_refused() {
    let s = subject(&golden("proxies"), false);
    let p = proxies();
    let (m, pf) = (s.model.cast_const(), p.frame);
    let (v, mut o) = ([0.0f32; 64], [0.0f32; 64]);
    let (v, out, nf) = (v.as_ptr(), o.as_mut_ptr(), null::<f32>());
    let (sk, skl) = (s.skinning.as_ptr(), s.skinning.len());
    let calls = [
        ("pose model", aprt_pose_proxies(null(), sk, skl, pf)),
        ("pose skinning", aprt_pose_proxies(m, nf, skl, pf)),
        ("pose frame", aprt_pose_proxies(m, sk, skl, null_mut())),
        (
            "occlude model",
            aprt_occlude(null(), pf, v, 4, v, v, 0, out, 1),
        ),
        (
            "occlude frame",
            aprt_occlude(m, null(), v, 4, v, v, 0, out, 1),
        ),
        (
            "occlude lighting",
            aprt_occlude(m, pf, nf, 4, v, v, 0, out, 1),
        ),
        (
            "occlude positions",
            aprt_occlude(m, pf, v, 4, nf, v, 0, out, 1),
        ),
        (
            "occlude normals",
            aprt_occlude(m, pf, v, 4, v, nf, 0, out, 1),
        ),
        (
            "occlude out",
            aprt_occlude(m, pf, v, 4, v, v, 0, null_mut(), 1),
        ),
        (
            "occlude_transfer model",
            aprt_occlude_transfer(null(), pf, v, 2, v, v, 0, 1, out, 4),
        ),
        (
            "occlude_transfer frame",
            aprt_occlude_transfer(m, null(), v, 2, v, v, 0, 1, out, 4),
        ),
        (
            "occlude_transfer bones",
            aprt_occlude_transfer(m, pf, nf, 2, v, v, 0, 1, out, 4),
        ),
        (
            "occlude_transfer positions",
            aprt_occlude_transfer(m, pf, v, 2, nf, v, 0, 1, out, 4),
        ),
        (
            "occlude_transfer normals",
            aprt_occlude_transfer(m, pf, v, 2, v, nf, 0, 1, out, 4),
        ),
        (
            "occlude_transfer out",
            aprt_occlude_transfer(m, pf, v, 2, v, v, 0, 1, null_mut(), 4),
        ),
    ];
    for (what, status) in calls {
        assert_eq!(status, NullPointer, "{what}");
    }
}

#[test]
fn misaligned_pointers_are_refused() {
    let s = subject(&golden("proxies"), false);
    let p = proxies();
    assert_eq!(s.pose(&p), OK);
    let (m, pf) = (s.model.cast_const(), p.frame);
    let (v, mut o) = ([0.25f32; 64], [0.0f32; 64]);
    let odd = |p: *const f32| p.cast::<u8>().wrapping_add(2).cast::<f32>();
    let (v, out) = (v.as_ptr(), o.as_mut_ptr());
    let (bad, bad_out) = (odd(v), odd(out).cast_mut());
    let bad_frame = pf.cast::<u8>().wrapping_add(4).cast::<aprt_proxy_frame>();
    let sk = s.skinning.as_ptr();
    let calls = [
        ("pose skinning", aprt_pose_proxies(m, odd(sk), 24, pf)),
        ("pose frame", aprt_pose_proxies(m, sk, 24, bad_frame)),
        (
            "occlude frame",
            aprt_occlude(m, bad_frame, v, 4, v, v, 0, out, 1),
        ),
        (
            "occlude lighting",
            aprt_occlude(m, pf, bad, 4, v, v, 0, out, 1),
        ),
        (
            "occlude positions",
            aprt_occlude(m, pf, v, 4, bad, v, 0, out, 1),
        ),
        (
            "occlude normals",
            aprt_occlude(m, pf, v, 4, v, bad, 0, out, 1),
        ),
        (
            "occlude out",
            aprt_occlude(m, pf, v, 4, v, v, 0, bad_out, 1),
        ),
        (
            "occlude_transfer bones",
            aprt_occlude_transfer(m, pf, bad, 2, v, v, 0, 1, out, 4),
        ),
        (
            "occlude_transfer positions",
            aprt_occlude_transfer(m, pf, v, 2, bad, v, 0, 1, out, 4),
        ),
        (
            "occlude_transfer normals",
            aprt_occlude_transfer(m, pf, v, 2, v, bad, 0, 1, out, 4),
        ),
        (
            "occlude_transfer out",
            aprt_occlude_transfer(m, pf, v, 2, v, v, 0, 1, bad_out, 4),
        ),
    ];
    for (what, status) in calls {
        assert_eq!(status, Misaligned, "{what}");
    }
}

#[test]
fn a_skinning_of_the_wrong_length_is_refused_and_leaves_no_proxies() {
    let s = subject(&golden("proxies"), false);
    let p = proxies();
    let bones = s.info.bones as usize;
    assert_eq!(bones, 2);
    let sk = s.skinning.as_ptr();
    let mut out = vec![0.0f32; 4];
    let long = [s.skinning.clone(), s.skinning[..12].to_vec()].concat();
    for (what, skinning, len) in [
        ("one float short", sk, 12 * bones - 1),
        ("one float over", long.as_ptr(), 12 * bones + 1),
        ("one bone short", sk, 12),
        ("one bone over", long.as_ptr(), 36),
        ("none", null(), 0),
    ] {
        // Posed first, then refused: the frame holds no proxies any more.
        assert_eq!(s.pose(&p), OK);
        assert_eq!(s.occlude(&p, 0, &mut out), OK);
        let status = aprt_pose_proxies(s.model, skinning, len, p.frame);
        assert_eq!(status, WrongLength, "{what}");
        let status = s.occlude(&p, 0, &mut out);
        assert_eq!(status, aprt_status::WeightsNotSet, "{what}");
    }
    let mut nan = s.skinning.clone();
    nan[12 + 7] = f32::NAN;
    let status = aprt_pose_proxies(s.model, nan.as_ptr(), nan.len(), p.frame);
    assert_eq!(status, aprt_status::BadSkinning);
}

#[test]
fn proxies_posed_by_another_model_are_refused() {
    let (a, b) = (
        subject(&golden("proxies"), false),
        subject(&seed_blob(), false),
    );
    assert_ne!(a.info.id, b.info.id);
    let count = a.n().min(b.n());
    for (posed, other) in [(&a, &b), (&b, &a)] {
        let p = proxies();
        assert_eq!(posed.pose(&p), OK);
        let mut out = vec![0.0f32; count];
        let status = other.occlude(&p, 0, &mut out);
        assert_eq!(status, aprt_status::WeightsForOtherModel);
        let mut transfer = vec![0.0f32; count * other.n2()];
        let status = other.occlude_transfer(&p, 0, &mut transfer);
        assert_eq!(status, aprt_status::WeightsForOtherModel);
        assert_eq!(posed.occlude(&p, 0, &mut out), OK);
    }
}

#[test]
fn a_model_without_proxies_says_so() {
    let has = subject(&golden("proxies"), false);
    let p = proxies();
    assert_eq!(has.pose(&p), OK);
    for kind in ["atlas", "bones", "world"] {
        for streamed in [false, true] {
            let s = subject(&golden(kind), streamed);
            let mut out = vec![0.0f32; s.n()];
            let mut transfer = vec![0.0f32; s.n() * s.n2()];
            // Whether the frame is empty or posed by another model: NoProxies.
            let empty = proxies();
            for frame in [&empty, &p] {
                assert_eq!(s.occlude(frame, 0, &mut out), NoProxies, "{kind}");
                let status = s.occlude_transfer(frame, 0, &mut transfer);
                assert_eq!(status, NoProxies, "{kind}");
            }
            let sk = vec![0.0f32; 12 * s.info.bones as usize];
            let status = aprt_pose_proxies(s.model, sk.as_ptr(), sk.len(), empty.frame);
            assert_eq!(status, NoProxies, "{kind}");
        }
    }
}

#[test]
fn occluding_before_posing_the_proxies_is_refused() {
    for streamed in [false, true] {
        let s = subject(&golden("proxies"), streamed);
        let p = proxies();
        let mut out = vec![0.0f32; s.n()];
        let mut transfer = vec![0.0f32; s.n() * s.n2()];
        assert_eq!(s.occlude(&p, 0, &mut out), aprt_status::WeightsNotSet);
        let status = s.occlude_transfer(&p, 0, &mut transfer);
        assert_eq!(status, aprt_status::WeightsNotSet);
        assert_eq!(s.pose(&p), OK);
        assert_eq!(s.occlude(&p, 0, &mut out), OK);
    }
}

#[test]
fn streamed_resident_and_the_core_agree_bit_for_bit() {
    for blob in [golden("proxies"), seed_blob()] {
        let (resident, streamed) = (subject(&blob, false), subject(&blob, true));
        let (shading, transfer) = resident.occluded();
        let (s_shading, s_transfer) = streamed.occluded();
        assert_eq!(bits(&shading), bits(&s_shading));
        assert_eq!(bits(&transfer), bits(&s_transfer));

        // The core called from Rust with the same inputs.
        let model = Model::parse(&blob).unwrap();
        let info = *model.info();
        let rotations: Vec<Rotation> = (0..info.bones()).map(rotation).collect();
        let skinning: Vec<Skinning> = resident
            .skinning
            .chunks_exact(12)
            .map(|m| m.try_into().unwrap())
            .collect();
        let triples = |v: &[f32]| -> Vec<[f32; 3]> {
            v.chunks_exact(3).map(|t| t.try_into().unwrap()).collect()
        };
        let (positions, normals) = (triples(&resident.positions), triples(&resident.normals));
        let (mut pose, mut lit) = (Box::new(PoseWeights::new()), Box::new(LitWeights::new()));
        let mut frame = Box::new(ProxyFrame::new());
        model
            .set_pose(&vec![0.1; info.pose_len()], &mut pose)
            .unwrap();
        model
            .light(&pose, &resident.sky, &rotations, &mut lit)
            .unwrap();
        let mut want = vec![0.0; info.vertices()];
        model.shade(&lit, 0, &mut want).unwrap();
        let plain = want.clone();
        let mut want_transfer = vec![0.0; info.vertices() * info.coeffs()];
        model.transfer(&pose, 0, &mut want_transfer).unwrap();
        let plain_transfer = want_transfer.clone();
        model.pose_proxies(&skinning, &mut frame).unwrap();
        let sky = &resident.sky;
        model
            .occlude(&frame, sky, &positions, &normals, 0, &mut want)
            .unwrap();
        model
            .occlude_transfer(
                &frame,
                &rotations,
                &positions,
                &normals,
                0,
                &mut want_transfer,
            )
            .unwrap();
        assert_eq!(bits(&shading), bits(&want));
        assert_eq!(bits(&transfer), bits(&want_transfer));
        // The proxies occlude some vertices and not others, so the test sees them.
        let changed = shading.iter().zip(&plain).filter(|(a, b)| a != b).count();
        assert!(changed > 0 && changed < shading.len(), "{changed} changed");
        assert_ne!(bits(&transfer), bits(&plain_transfer));

        // A sub-range occludes what the whole mesh does there, resident and streamed.
        let (first, count) = (3, resident.n() - 5);
        for s in [&resident, &streamed] {
            let p = proxies();
            assert_eq!(s.pose(&p), OK);
            let mut part = plain[first..first + count].to_vec();
            assert_eq!(s.occlude(&p, first, &mut part), OK);
            assert_eq!(bits(&part), bits(&shading[first..first + count]));
            let n2 = s.n2();
            let mut part = plain_transfer[first * n2..(first + count) * n2].to_vec();
            assert_eq!(s.occlude_transfer(&p, first, &mut part), OK);
            let whole = &transfer[first * n2..(first + count) * n2];
            assert_eq!(bits(&part), bits(whole));
            // Past the last vertex is a range error.
            let (sky, mut over) = (&s.sky, [0.0f32; 3]);
            let (pos, nor) = (s.positions.as_ptr(), s.normals.as_ptr());
            let (last, o) = (s.n() - 2, over.as_mut_ptr());
            let status = aprt_occlude(
                s.model,
                p.frame,
                sky.as_ptr(),
                sky.len(),
                pos,
                nor,
                last,
                o,
                3,
            );
            assert_eq!(status, aprt_status::VertexRange);
        }
    }
}
