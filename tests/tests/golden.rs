//! Golden blobs: small models of each frame, checked into `fixtures/golden/`, that every later
//! reader must keep reading the same way (the format's compatibility promise) and that the
//! core's documentation examples run on. `cargo run -p aprt-tests --release --example
//! write_golden` writes them again from the models in `aprt_tests::golden`.

use aprt_core::{Frame, Model};
use aprt_tests::decode::decode;
use aprt_tests::golden::{encode, golden_dir, golden_models};
use aprt_tests::harness::{Probe, exercise};

/// Each checked-in blob reads with the dimensions and names it was written with, evaluates
/// like the f64 reference of what it stores (resident and streamed, through the fuzz
/// harness), and is what the writer writes today.
#[test]
fn golden_blobs_read_as_written() {
    for golden in golden_models() {
        let (name, model, _, atlas) = &golden;
        let path = golden_dir().join(name);
        let blob = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let core = Model::parse(&blob).unwrap_or_else(|e| panic!("{name}: {e}"));
        let info = core.info();
        assert_eq!(
            (
                info.order(),
                info.vertices(),
                info.pose_len(),
                info.pose_dims()
            ),
            (
                model.order,
                model.vertices,
                model.pose_len,
                model.pose_dims()
            ),
            "{name}"
        );
        assert_eq!(info.coef_dims(), model.coef_dims(), "{name}");
        let bones = model.bones.as_ref().map_or(0, |b| b.count);
        assert_eq!(info.bones(), bones, "{name}");
        assert_eq!(info.frame() == Frame::World, bones == 0, "{name}");
        assert!(
            core.angle_names()
                .iter()
                .eq(model.angle_names.iter().map(String::as_str))
        );
        let stored = decode(&blob).unwrap();
        assert_eq!(stored.angle_names, model.angle_names, "{name}");
        let read = core.texel_atlas().map(|a| {
            let texels = (0..a.rows()).map(|j| a.texel(j).unwrap()).collect();
            let uvs = (0..a.triangles()).map(|t| a.corner_uvs(t).unwrap());
            (a.resolution(), texels, uvs.collect())
        });
        assert_eq!(read, *atlas, "{name}: texel atlas");
        assert_eq!(
            info.has_proxies(),
            model.proxies.is_some(),
            "{name}: proxies"
        );
        assert_eq!(stored.proxies, model.proxies, "{name}: proxies");
        exercise(&blob, &Probe::GENTLE).unwrap();
        assert!(
            encode(&golden) == blob,
            "{name}: the writer's bytes changed; if that is intended, keep this blob as a \
             compatibility fixture and write the new one under a new name"
        );
    }
}
