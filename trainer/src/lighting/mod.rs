//! Lighting: the lights file, environment maps projected to SH, irradiance at a point through
//! the SH path next to the exact closed form (*Irradiance Rigs*, Yuan, Nowrouzezahrai and
//! Sloan, eq. 2), and the grey levels and luminance every error is shown in. The formulas live
//! in `aprt_core` (`Light`), so engines and the trainer evaluate the same ones; the rigs that
//! carry lights over a character are `irradiance_rig/`.

pub mod env_map;
pub mod lights_file;

use aprt_core::{Light, LightError, MAX_COEFFS, Rgb, Window, apply_window, irradiance_sh};
use serde::Serialize;

pub use env_map::{
    EnvMapError, EnvironmentImage, decode_equirect, project_equirect, read_environment,
    read_equirect,
};
pub use lights_file::{LightsFileError, finite_f32s, light_from_table, parse_lights, read_lights};

/// Grey levels per unit of irradiance: the radiance a white Lambertian surface reflects,
/// `E / π`, on an 8-bit display where radiance 1 is white.
pub const GREY_PER_IRRADIANCE: f64 = 255.0 / std::f64::consts::PI;

/// Rec. 709 luminance: the one channel the model's shading takes of RGB lighting, and how an
/// RGB shading is shown in grey.
pub fn luminance(c: Rgb) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// One light's share of an [`IrradianceReport`].
#[derive(Clone, Debug, Serialize)]
pub struct LightIrradiance {
    /// `sphere`, `point` or `directional`.
    pub kind: &'static str,
    /// Its irradiance through the SH path.
    pub sh: Rgb,
    /// Its exact unshadowed irradiance.
    pub exact: Rgb,
}

/// Irradiance at a point and normal, through SH and exactly, summed over lights.
#[derive(Clone, Debug, Serialize)]
pub struct IrradianceReport {
    /// SH order of the SH path.
    pub order: usize,
    /// The point.
    pub at: [f32; 3],
    /// The surface normal.
    pub normal: [f32; 3],
    /// The deringing window applied to each light's SH radiance, if any.
    pub window: Option<&'static str>,
    /// Irradiance through the SH path, `Σ Â_l L_lm y_lm(n)`.
    pub sh: Rgb,
    /// Exact unshadowed irradiance (sphere lights clipped by the horizon in closed form).
    pub exact: Rgb,
    /// `|sh − exact|` per channel.
    pub abs_error: Rgb,
    /// `255 |sh − exact| / π` per channel: the error in the radiance a white Lambertian
    /// surface reflects, in grey levels of an 8-bit display where radiance 1 is white.
    pub grey_levels: Rgb,
    /// Each light's share, in file order.
    pub lights: Vec<LightIrradiance>,
}

/// Why a light could not be evaluated at the point.
#[derive(Debug, thiserror::Error)]
#[error("light {index} ({kind}): {error}")]
pub struct LightEvalError {
    /// Its position in the list, from 1.
    pub index: usize,
    /// Its kind.
    pub kind: &'static str,
    /// What the core refused.
    pub error: LightError,
}

/// Why irradiance at a point could not be reported.
#[derive(Debug, thiserror::Error)]
pub enum IrradianceError {
    /// A light the core could not evaluate there.
    #[error(transparent)]
    Light(#[from] LightEvalError),
    /// A figure of the report is beyond f32 (lights each finite whose sum or error is not),
    /// which JSON would print as `null`.
    #[error(
        "the {figure} is {value:?}, beyond f32 (up to {max:e}), the precision lights are evaluated in: scale the lights down",
        max = f32::MAX
    )]
    Overflow {
        /// Which figure.
        figure: &'static str,
        /// Its RGB.
        value: Rgb,
    },
}

/// The kind's name, as the lights file spells it.
pub fn kind_name(light: &Light) -> &'static str {
    match light {
        Light::Sphere(_) => "sphere",
        Light::Point(_) => "point",
        Light::Directional(_) => "directional",
    }
}

/// The window's name, as `--dering` spells it.
pub fn window_name(window: Window) -> &'static str {
    match window {
        Window::Hann => "hann",
        Window::Lanczos => "lanczos",
    }
}

/// Irradiance at `at` on a surface of `normal` from `lights`, through SH of `order` (each
/// light's radiance optionally windowed) and exactly.
pub fn irradiance(
    lights: &[Light],
    at: [f32; 3],
    normal: [f32; 3],
    order: usize,
    window: Option<Window>,
) -> Result<IrradianceReport, IrradianceError> {
    let mut report = IrradianceReport {
        order,
        at,
        normal,
        window: window.map(window_name),
        sh: [0.0; 3],
        exact: [0.0; 3],
        abs_error: [0.0; 3],
        grey_levels: [0.0; 3],
        lights: Vec::with_capacity(lights.len()),
    };
    for (i, light) in lights.iter().enumerate() {
        let kind = kind_name(light);
        let fail = |error| LightEvalError {
            index: i + 1,
            kind,
            error,
        };
        let mut sh = [[0.0f32; 3]; MAX_COEFFS];
        let n2 = order * order;
        light
            .add_radiance_sh(order, at, &mut sh[..n2.min(MAX_COEFFS)])
            .map_err(fail)?;
        if let Some(w) = window {
            apply_window(order, w, &mut sh).map_err(fail)?;
        }
        let e_sh = irradiance_sh(order, &sh, normal).map_err(fail)?;
        let e_exact = light.irradiance(at, normal).map_err(fail)?;
        for k in 0..3 {
            report.sh[k] += e_sh[k];
            report.exact[k] += e_exact[k];
        }
        report.lights.push(LightIrradiance {
            kind,
            sh: e_sh,
            exact: e_exact,
        });
    }
    for k in 0..3 {
        report.abs_error[k] = (report.sh[k] - report.exact[k]).abs();
        report.grey_levels[k] = 255.0 * report.abs_error[k] / std::f32::consts::PI;
    }
    for (figure, value) in [
        ("irradiance through SH", report.sh),
        ("exact irradiance", report.exact),
        ("error in grey levels", report.grey_levels),
    ] {
        if !value.iter().all(|v| v.is_finite()) {
            return Err(IrradianceError::Overflow { figure, value });
        }
    }
    Ok(report)
}
