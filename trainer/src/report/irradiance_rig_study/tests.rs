//! The study's core loop on a reduced setting (three rigs, two directions, every 8th vertex,
//! no timing, no novel-pose fits): properties that must hold whatever the numbers.

use super::setup::{DISTANCES, RigChoice, directions, rigs};
use super::*;

#[test]
fn reduced_study_errors_fall_with_distance_and_the_json_has_its_keys() {
    let creature = Creature::builtin();
    let poses = poses(&creature).unwrap();
    let all = rigs();
    let chosen: Vec<RigChoice> = [0, 1, setup::MIXED_6]
        .into_iter()
        .map(|i| all[i].clone())
        .collect();
    let settings = StudySettings {
        order: 3,
        rigs: chosen,
        directions: directions().into_iter().take(2).collect(),
        sweep: DISTANCES.iter().map(|d| d.1).collect(),
        vertex_step: 8,
        novel: false,
        timed: false,
    };
    let m = measure(&poses, &settings);
    for r in &m.rigs {
        for c in r.lash.iter().chain(&r.bind) {
            for a in [&c.exact, &c.added] {
                assert!(a.mean.is_finite() && a.max.is_finite(), "{}", r.choice.kind);
                assert!(
                    a.each
                        .iter()
                        .all(|e| e.mean.is_finite() && e.max.is_finite())
                );
            }
        }
        // What the rig adds to per-vertex SH falls from mid to far distance. Not from near to
        // mid: the normalised light grows as (d - 1)^2 and the creature's flanks are far
        // inside its bounding sphere (docs/rigs). Nor against exact: the SH truncation grows
        // with the light.
        for cells in [&r.lash, &r.bind] {
            let (mid, far) = (&cells[1].added, &cells[2].added);
            assert!(
                far.max < mid.max && far.mean < mid.mean,
                "{}: mid {:?} then far {:?}",
                r.choice.kind,
                (mid.mean, mid.max),
                (far.mean, far.max)
            );
        }
    }
    let (constant, gradient) = (&m.rigs[0].lash[1].exact, &m.rigs[1].lash[1].exact);
    assert!(
        gradient.max < constant.max && gradient.mean < constant.mean,
        "gradient {gradient:?} against constant {constant:?} at mid distance"
    );
    let json = to_json(&m, "test").unwrap();
    for key in ["settings", "measured", "claim"] {
        assert!(json.get(key).is_some(), "{key}");
    }
    let measured = &json["measured"];
    for key in [
        "order",
        "centre",
        "radius",
        "directions",
        "sweep",
        "rigs",
        "floor_lash",
        "floor_bind",
    ] {
        assert!(measured.get(key).is_some(), "measured.{key}");
    }
    let rig = &measured["rigs"][0];
    for key in [
        "choice",
        "sh_vectors",
        "us_per_frame",
        "table",
        "lash",
        "bind",
        "novel",
    ] {
        assert!(rig.get(key).is_some(), "rigs[0].{key}");
    }
    for measure in ["exact", "added"] {
        let a = &rig["lash"][0][measure];
        assert!(
            a.get("mean").is_some() && a.get("max").is_some(),
            "{measure}"
        );
    }
}
