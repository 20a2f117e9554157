//! Occluder proxies through the binary: `--proxies on` writes them into the blob (a required
//! section aprt-core reads), `--proxies none` leaves them out, the selection says what they
//! did, and `aprt eval` subtracts their occlusion on the clip's posed meshes.

use aprt_core::Model;
use run::{aprt, read_npy, succeed};

use crate::run;

#[test]
fn proxies_are_written_when_asked_and_evaluated_on_the_clip() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let source = ["--builtin", "--clip", "wave", "--order", "2", "--rays", "4"];
    let train = |proxies: &str, model: &str| {
        let args = [
            &["train"][..],
            &source,
            &["--proxies", proxies, "-o", model],
        ]
        .concat();
        let out = aprt(&args);
        assert!(out.status.success(), "{args:?}");
        String::from_utf8(out.stderr).unwrap()
    };
    let (with, without) = (path("with.aprt"), path("without.aprt"));
    let printed = train("on", &with);
    assert!(
        printed.contains("occluder proxies:") && printed.contains("kept"),
        "the selection says what the proxies did:\n{printed}"
    );
    train("none", &without);
    let has = |file: &str| {
        let blob = std::fs::read(file).unwrap();
        Model::parse(&blob).unwrap().info().has_proxies()
    };
    assert!(has(&with) && !has(&without));
    let npy = path("eval.npy");
    let args = [&["eval", &with][..], &source[..3], &["--npy", &npy]].concat();
    succeed(&args);
    let (shape, values) = read_npy(std::path::Path::new(&npy));
    assert_eq!(shape[2], 4);
    assert!(values.iter().all(|x| x.is_finite()));
}
