//! Planning a scene: from what the scene file asks for (`crate::scene::file`), derive what to
//! compute and nothing else: no visibility rays without shadows, no bounce pass without
//! bounces, the lowest SH order the lighting needs at the error target, no irradiance rig when
//! the lights are far enough, the smallest precision within the target. Each decision is
//! recorded as a sentence, so `aprt train --scene --report` and `aprt demo` can say what was
//! computed and what was skipped.

pub mod file;
pub mod frame_cost;
pub mod irradiance_rig_choice;
pub mod lighting;
pub mod method;
pub mod order;

use aprt_core::MAX_ORDER;

use crate::bake::BakeSettings;
use crate::rig::mesh::Mesh;
use crate::scene::file::{Choice, Scene};
use lighting::SceneLighting;
use order::{OrderChoice, choose_order};

/// The bake a scene needs and the sentences that say why.
#[derive(Clone, Debug)]
pub struct BakePlan {
    /// What to simulate.
    pub bake: BakeSettings,
    /// The SH order and why.
    pub order: OrderChoice,
    /// What is computed, one sentence each.
    pub computed: Vec<String>,
    /// What is skipped, one sentence each.
    pub skipped: Vec<String>,
}

/// The bake `scene` needs, its SH order checked against `lighting` at `bind`'s vertices.
/// `poses` is how many poses the bake covers, for the sentences' counts. Refused, naming the
/// scene, when the lighting's figures are beyond f32.
pub fn plan_bake(
    scene: &Scene,
    lighting: &SceneLighting,
    bind: &Mesh,
    poses: usize,
) -> anyhow::Result<BakePlan> {
    let e = &scene.effects;
    let mut order = choose_order(lighting, bind, e.error_target)
        .map_err(|m| anyhow::anyhow!("{}: lighting: {m}", scene.path.display()))?;
    if let Choice::Fixed(n) = e.order {
        order.reason = format!(
            "order {n}, as the scene asks (the lighting alone would need order {}: {})",
            order.order, order.reason
        );
        order.order = n;
    }
    let bake = BakeSettings {
        order: order.order,
        rays: e.rays,
        bounces: e.bounces,
        albedo: e.albedo,
        shadows: e.shadows,
    };
    let v = bind.vertex_count();
    let mut computed = vec![format!(
        "SH order {} ({} coefficients per vertex): {}",
        order.order,
        order.order * order.order,
        order.reason
    )];
    let mut skipped = Vec::new();
    if e.shadows {
        computed.push(shadows_sentence(&bake, (v, "vertex"), poses));
    } else {
        skipped.push(format!(
            "visibility rays: the scene casts no shadows, so each vertex's transfer is the clamped cosine lobe turned to its normal, in closed form (0 rays instead of {})",
            group(e.rays as u64 * v as u64 * poses as u64)
        ));
    }
    if e.bounces == 0 {
        skipped.push("inter-reflection: bounces = 0, so no bounce pass".into());
    } else {
        computed.push(format!(
            "{} bounce pass(es) at albedo {}, gathering at the direct pass's hits (no extra rays)",
            e.bounces, e.albedo
        ));
    }
    let unused = MAX_ORDER * MAX_ORDER - order.order * order.order;
    if unused > 0 {
        let bands = match order.order {
            n if n + 1 == MAX_ORDER => format!("band {n}"),
            n => format!("bands {n} to {}", MAX_ORDER - 1),
        };
        skipped.push(format!(
            "{unused} of the {} coefficients the runtime holds ({bands}): neither baked nor stored",
            MAX_ORDER * MAX_ORDER
        ));
    }
    Ok(BakePlan {
        bake,
        order,
        computed,
        skipped,
    })
}

/// How the sentence on the shadows a bake computes begins.
pub const SHADOWS: &str = "shadows:";

/// The sentence on the visibility rays `bake` casts at `points` (a count and what each is,
/// `"vertex"` or `"texel"`) of each of `poses` poses.
pub fn shadows_sentence(
    bake: &BakeSettings,
    (points, unit): (usize, &str),
    poses: usize,
) -> String {
    let units = match unit {
        "vertex" => "vertices".to_owned(),
        other => format!("{other}s"),
    };
    format!(
        "{SHADOWS} {} visibility rays ({} per {unit}, {points} {units}, {poses} poses)",
        group(bake.rays_cast(points) * poses as u64),
        bake.rays
    )
}

/// `n` with commas between thousands, as the reports print counts.
pub fn group(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}
