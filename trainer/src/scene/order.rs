//! The SH order a scene needs: the lowest whose truncation keeps the unshadowed irradiance of
//! the scene's lighting within the error target at the character's surface.
//!
//! Irradiance is the clamped cosine lobe convolved with the radiance, and the lobe's bands fall
//! fast (`Â_l`: π, 2π/3, π/4, 0, −π/24, 0, π/64), so a smooth environment is done at order 3;
//! a small, bright, near light puts energy in high bands at the points close to it, and only
//! such a light asks for more. The check runs at the bind pose's vertices (up to
//! [`MAX_POINTS`] of them), against the environment at every band it has and each light's
//! exact horizon-clipped irradiance. Shadowed transfer is the same lobe cut by visibility; its
//! own truncation error is what the report's sweep over orders measures.

use aprt_core::{Light, MAX_ORDER};

use super::lighting::{SceneLighting, grey_error};
use crate::rig::mesh::Mesh;

/// Vertices of the bind pose the check visits at most (evenly spaced by index).
pub const MAX_POINTS: usize = 2000;

/// The order chosen and why, in one sentence.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct OrderChoice {
    /// The order.
    pub order: usize,
    /// Why.
    pub reason: String,
    /// The worst irradiance error at each order 1..=6, in grey levels.
    pub grey_by_order: Vec<f32>,
}

/// The vertices the check visits: at most [`MAX_POINTS`], evenly spaced by index.
fn points(mesh: &Mesh) -> std::iter::StepBy<std::ops::Range<usize>> {
    let step = mesh.vertex_count().div_ceil(MAX_POINTS).max(1);
    (0..mesh.vertex_count()).step_by(step)
}

/// The worst truncation error at `order` over the points, the part (0: the environment,
/// `i`: light `i`) whose own error is the largest there, and the points left out (where a
/// part has no value, see [`SceneLighting::irradiance_parts`]). An error when a figure is beyond f32, the precision shading is computed in: a
/// choice made on it would be made on nothing.
fn worst_error(
    lighting: &SceneLighting,
    mesh: &Mesh,
    order: usize,
) -> Result<(f32, usize, usize), String> {
    let (mut worst, mut culprit, mut skipped) = (0.0f32, 0usize, 0usize);
    for j in points(mesh) {
        let beyond = |what: String| {
            format!(
                "at bind-pose vertex {j}, {what}: the lighting is too bright for f32, the precision it is shaded in; scale it down"
            )
        };
        let Some(parts) = lighting
            .irradiance_parts(order, mesh.positions[j], mesh.normals[j])
            .map_err(beyond)?
        else {
            skipped += 1;
            continue;
        };
        let total = parts
            .iter()
            .fold(([0.0f32; 3], [0.0f32; 3]), |(s, e), (ps, pe)| {
                (
                    std::array::from_fn(|k| s[k] + ps[k]),
                    std::array::from_fn(|k| e[k] + pe[k]),
                )
            });
        let error = grey_error(total.0, total.1);
        if !error.is_finite() {
            return Err(beyond(format!(
                "the order-{order} irradiance error is {error} grey levels"
            )));
        }
        if error > worst {
            worst = error;
            culprit = parts
                .iter()
                .enumerate()
                .max_by(|a, b| grey_error(a.1.0, a.1.1).total_cmp(&grey_error(b.1.0, b.1.1)))
                .map_or(0, |(i, _)| i);
        }
    }
    Ok((worst, culprit, skipped))
}

/// What part `i` of [`SceneLighting::irradiance_parts`] is, and why it needs high bands,
/// for a sentence.
fn part_name(lighting: &SceneLighting, part: usize) -> String {
    let Some(light) = part.checked_sub(1).and_then(|i| lighting.lights.get(i)) else {
        return "the environment's high bands".to_owned();
    };
    let why = match light {
        Light::Directional(_) => {
            "a directional light: its irradiance has a kink at the terminator that no finite order holds; a sphere light of some size, or a larger target, meets it"
        }
        _ => {
            "a compact bright light: the sharper a light, the more bands its irradiance needs; an irradiance rig evaluates a near one per vertex"
        }
    };
    format!(
        "light {part} ({}, {why})",
        crate::lighting::kind_name(light)
    )
}

/// The lowest order that keeps the worst irradiance error at `mesh`'s vertices within
/// `target` grey levels (order 6 when none does, saying which part of the lighting misses);
/// an error when the lighting's figures are beyond f32.
pub fn choose_order(
    lighting: &SceneLighting,
    mesh: &Mesh,
    target: f32,
) -> Result<OrderChoice, String> {
    let errors: Vec<(f32, usize, usize)> = (1..=MAX_ORDER)
        .map(|n| worst_error(lighting, mesh, n))
        .collect::<Result<_, _>>()?;
    let grey_by_order: Vec<f32> = errors.iter().map(|e| e.0).collect();
    let visited = points(mesh).len();
    let skipped = match errors[0].2 {
        0 => String::new(),
        s => format!("; {s} vertices where a light cannot be evaluated are left out"),
    };
    Ok(match grey_by_order.iter().position(|&e| e <= target) {
        Some(0) => OrderChoice {
            order: 1,
            reason: format!(
                "order 1 meets {target} grey level(s): the lighting's worst irradiance error over {visited} bind-pose vertices is {:.2}{skipped}",
                grey_by_order[0]
            ),
            grey_by_order,
        },
        Some(i) => {
            let (miss, culprit, _) = errors[i - 1];
            OrderChoice {
                order: i + 1,
                reason: format!(
                    "order {} is the lowest that meets {target} grey level(s) over {visited} bind-pose vertices ({:.2}); order {i} misses it ({miss:.2}), most from {}{skipped}",
                    i + 1,
                    grey_by_order[i],
                    part_name(lighting, culprit)
                ),
                grey_by_order,
            }
        }
        None => {
            let (miss, culprit, _) = errors[MAX_ORDER - 1];
            OrderChoice {
                order: MAX_ORDER,
                reason: format!(
                    "no order meets {target} grey level(s): order {MAX_ORDER} still misses by {miss:.2}, most from {}{skipped}",
                    part_name(lighting, culprit),
                ),
                grey_by_order,
            }
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use aprt_core::{DirectionalLight, SphereLight};

    /// A unit sphere of vertices with outward normals.
    fn ball() -> Mesh {
        let mut positions = Vec::new();
        for i in 0..40 {
            for k in 0..20 {
                let (phi, z) = (i as f32 * 0.157, -0.95 + k as f32 * 0.1);
                let r = (1.0 - z * z).sqrt();
                positions.push([r * phi.cos(), r * phi.sin(), z]);
            }
        }
        Mesh {
            normals: positions.clone(),
            positions,
            triangles: Vec::new(),
        }
    }

    fn environment(coefficients: &[[f32; 3]]) -> SceneLighting {
        SceneLighting {
            environment: coefficients.to_vec(),
            lights: Vec::new(),
        }
    }

    /// A constant environment is band 0 alone: order 1 is exact.
    #[test]
    fn a_constant_environment_needs_order_one() {
        let choice = choose_order(&environment(&[[1.0, 1.0, 1.0]]), &ball(), 1.0).unwrap();
        assert_eq!(choice.order, 1, "{}", choice.reason);
        assert!(choice.grey_by_order.iter().all(|&e| e < 1e-3));
    }

    /// Band 3 of an environment is invisible to irradiance (`Â_3 = 0`), band 2 is not:
    /// an environment with a band-2 term needs order 3 and no more.
    #[test]
    fn a_smooth_environment_needs_order_three() {
        let mut env = vec![[0.0f32; 3]; 16];
        env[0] = [2.0; 3];
        env[2] = [0.5; 3];
        env[6] = [0.4; 3];
        env[12] = [0.4; 3];
        let choice = choose_order(&environment(&env), &ball(), 1.0).unwrap();
        assert_eq!(choice.order, 3, "{}", choice.reason);
        // Order 2 misses by the band-2 term: Â_2 · 0.4 · y_20(n), largest at the ball's
        // poles, |z| = 0.95: y_20 = √(5/16π) (3z² − 1).
        let y20 = (5.0 / (16.0 * std::f32::consts::PI)).sqrt() * (3.0 * 0.95f32.powi(2) - 1.0);
        let expect = std::f32::consts::FRAC_PI_4 * 0.4 * y20 * 255.0 / std::f32::consts::PI;
        assert!((choice.grey_by_order[1] - expect).abs() < 0.05 * expect);
    }

    /// A directional light is a delta: its truncation error at order 3 is a few percent of
    /// its irradiance, so a bright sun needs a higher order than a dim one.
    #[test]
    fn a_bright_small_light_asks_for_more_than_a_dim_one() {
        let sun = |e: f32| SceneLighting {
            environment: Vec::new(),
            lights: vec![Light::Directional(DirectionalLight {
                direction: [0.3, 0.9, 0.1],
                irradiance: [e; 3],
            })],
        };
        let dim = choose_order(&sun(0.05), &ball(), 1.0).unwrap();
        let bright = choose_order(&sun(3.0), &ball(), 1.0).unwrap();
        assert!(dim.order <= 3, "{}", dim.reason);
        assert!(
            bright.order > dim.order,
            "{} / {}",
            bright.reason,
            dim.reason
        );
        assert!(
            bright.reason.contains("light 1 (directional"),
            "{}",
            bright.reason
        );
    }

    /// A sphere light touching the surface misses at every order and the reason says so.
    #[test]
    fn a_light_at_the_surface_is_named_when_no_order_suffices() {
        let lighting = SceneLighting {
            environment: Vec::new(),
            lights: vec![Light::Sphere(SphereLight {
                position: [0.0, 0.0, 1.06],
                radius: 0.05,
                radiance: [200.0; 3],
            })],
        };
        let choice = choose_order(&lighting, &ball(), 1.0).unwrap();
        assert_eq!(choice.order, MAX_ORDER);
        assert!(
            choice.reason.contains("no order meets"),
            "{}",
            choice.reason
        );
        assert!(
            choice.reason.contains("light 1 (sphere"),
            "{}",
            choice.reason
        );
    }
}
