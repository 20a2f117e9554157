//! What the study runs: the rigs (in the creature's axes, with the paper's spelling beside
//! them), the light placements normalised as in *Irradiance Rigs* section 3.1, and the poses.

use aprt_core::{Light, SphereLight};
use serde::Serialize;

use crate::irradiance_rig::RigKind;

/// A rig of the study: its kind as `--rig` spells it and what the paper calls it.
#[derive(Clone, Debug, Serialize)]
pub struct RigChoice {
    /// `--rig` spelling, in the creature's axes (x across, y along, z up).
    pub kind: String,
    /// The paper's name, in its axes (length, height, width).
    pub paper: String,
}

impl RigChoice {
    fn new(kind: &str, paper: &str) -> RigChoice {
        RigChoice {
            kind: kind.into(),
            paper: paper.into(),
        }
    }

    /// The parsed kind. The study's spellings are fixed and valid.
    pub fn parsed(&self) -> RigKind {
        self.kind.parse().expect("the study's rig kinds parse")
    }
}

/// Index of the 64-vector lattice in [`rigs`] (the paper's 8×4×2 in the creature's axes).
pub const LATTICE_64: usize = 3;
/// Index of the paper's six-vector mixed rig in [`rigs`].
pub const MIXED_6: usize = 4;

/// The rigs: the centroid probe, the gradient, the paper's 2×2×3 and 8×4×2 lattices and its
/// mixed rig in the creature's axes, then the last two spelled literally (paper axes read as
/// x, y, z), to show what the axis choice costs.
pub fn rigs() -> Vec<RigChoice> {
    vec![
        RigChoice::new("constant", "constant (centroid probe)"),
        RigChoice::new("gradient", "gradient"),
        RigChoice::new("lattice:2x3x2", "2×2×3 lattice, 3 along the length"),
        RigChoice::new("lattice:2x8x4", "8×4×2 lattice"),
        RigChoice::new(
            "mixed:x=constant,y=lattice3,z=gradient",
            "mixed: lattice3 length, gradient height, constant width",
        ),
        RigChoice::new("lattice:8x4x2", "8×4×2 spelled literally (8 across)"),
        RigChoice::new(
            "mixed:x=lattice3,y=gradient,z=constant",
            "mixed spelled literally (lattice3 across, gradient along)",
        ),
    ]
}

/// A direction from the rig's centre to a light.
#[derive(Clone, Debug, Serialize)]
pub struct Direction {
    /// Short name.
    pub name: String,
    /// Unit vector, root frame.
    pub vector: [f64; 3],
}

fn direction(name: &str, v: [f64; 3]) -> Direction {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    Direction {
        name: name.into(),
        vector: v.map(|c| c / n),
    }
}

/// The light directions: beyond the tail tip, beyond the head, above, beside either flank, and
/// two diagonals (tail, left and up; head, right and up).
pub fn directions() -> Vec<Direction> {
    vec![
        direction("+y (tail)", [0.0, 1.0, 0.0]),
        direction("-y (head)", [0.0, -1.0, 0.0]),
        direction("+z (above)", [0.0, 0.0, 1.0]),
        direction("+x (left flank)", [1.0, 0.0, 0.0]),
        direction("-x (right flank)", [-1.0, 0.0, 0.0]),
        direction("+x+y+z", [1.0, 1.0, 1.0]),
        direction("-x-y+z", [-1.0, -1.0, 1.0]),
    ]
}

/// The table's distances from the rig's centre, in radii: near, mid and far.
pub const DISTANCES: [(&str, f64); 3] = [("near", 1.25), ("mid", 2.5), ("far", 8.0)];
/// The plot's distances, in radii (the table's among them).
pub const SWEEP: [f64; 13] = [
    1.1, 1.25, 1.5, 2.0, 2.5, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0, 24.0, 32.0,
];
/// Radius of the sphere lights, as a share of the character's radius R.
pub const LIGHT_RADIUS: f64 = 0.05;
/// Far-field irradiance of every light at the nearest point of the bounding sphere: π, so a
/// white Lambertian surface facing the light there reflects radiance 1, 255 grey levels (the
/// paper's normalisation, "reflected radiance … is 1"). `π r² L = (d − R)²` would give
/// irradiance 1 instead, 81 grey levels; every error here is π times what it would give.
pub const NEAREST_IRRADIANCE: f64 = std::f64::consts::PI;

/// A sphere light of radius [`LIGHT_RADIUS`]·R at `d` radii from `centre` along `dir`, its
/// radiance set so `π r² L / ((d − 1) R)² =` [`NEAREST_IRRADIANCE`].
pub fn normalised_light(centre: [f64; 3], radius: f64, d: f64, dir: [f64; 3]) -> Light {
    let r = LIGHT_RADIUS * radius;
    let gap = (d - 1.0) * radius;
    let radiance = NEAREST_IRRADIANCE * gap * gap / (std::f64::consts::PI * r * r);
    Light::Sphere(SphereLight {
        position: std::array::from_fn(|k| (centre[k] + d * radius * dir[k]) as f32),
        radius: r as f32,
        radiance: [radiance as f32; 3],
    })
}

/// A pose of the creature the rigs are evaluated on.
#[derive(Clone, Debug, Serialize)]
pub struct PoseChoice {
    /// `bind`, or the clip's name.
    pub clip: String,
    /// Frame of the clip (0 for the bind pose).
    pub frame: usize,
}

/// The `lash` frame of the table and the renders: 2.67 s in, the tail curled beside the left
/// flank (+x) and the neck turned towards it.
pub const LASH_FRAME: usize = 80;
/// The frames of the novel-pose table: `lash` whipping, curling and curled; `prowl` over a
/// stride.
pub const NOVEL_FRAMES: [(&str, [usize; 3]); 2] = [("lash", [30, 60, 80]), ("prowl", [16, 40, 64])];
