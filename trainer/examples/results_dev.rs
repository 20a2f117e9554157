use aprt_trainer::results::*;
use aprt_trainer::{BakeSettings, Character, Rig};
fn main() {
    let c = Character::builtin();
    let s = |n: &str| {
        c.clip(n)
            .unwrap()
            .frames
            .into_iter()
            .step_by(6)
            .collect::<Vec<_>>()
    };
    let study = Study {
        id: "builtin".into(),
        title: "Built-in".into(),
        about: "dev".into(),
        up: glam::Vec3::Z,
        train: ("training".into(), s("training")),
        tests: vec![("wave".into(), s("wave")), ("walk".into(), s("walk"))],
        rig: Box::new(c.clone()),
    };
    let settings = ResultsSettings {
        bake: BakeSettings {
            order: 3,
            rays: 32,
            bounces: 0,
            albedo: 0.0,
        },
        alphas: (-6..=3).map(|e| 10f64.powi(e)).collect(),
    };
    let p = write_document(&[study], &settings, std::path::Path::new("/tmp/res"), "dev").unwrap();
    println!("{}", p.display());
}
