//! The lights file: `[[light]]` tables, each a sphere, point or directional light, read into
//! the core's [`Light`]s. A scene file embeds the same tables; [`light_from_table`] reads one.
//!
//! ```toml
//! [[light]]
//! kind = "sphere"             # uniform emitted radiance over a sphere
//! position = [0.0, 1.2, 0.8]
//! radius = 0.1
//! radiance = [4.0, 3.5, 3.0]  # RGB
//! [[light]]
//! kind = "point"
//! position = [1.0, 2.0, 0.0]
//! intensity = [2.0, 2.0, 2.0] # radiant intensity I: irradiance I / d^2 at normal incidence
//! [[light]]
//! kind = "directional"
//! direction = [0.3, 0.9, 0.2] # towards the light
//! irradiance = [1.0, 1.0, 1.0] # at normal incidence
//! ```

use std::path::{Path, PathBuf};

use aprt_core::{DirectionalLight, Light, PointLight, SphereLight};
use serde::Deserialize;

/// Most lights one file or scene may hold. A real-time frame lights a character with a
/// handful to a few dozen lights (a clustered renderer caps a cluster at a few hundred); every
/// light here is evaluated at every vertex of every frame, which for 100k lights ran over an
/// hour (about 36 ms a light), so 1024 lights stay within a minute and far above any scene of
/// this project (at most 3 lights).
pub const MAX_LIGHTS: usize = 1024;

/// Refuses `count` lights beyond [`MAX_LIGHTS`], before any is read or evaluated.
pub fn check_light_count(count: usize) -> Result<(), String> {
    if count <= MAX_LIGHTS {
        return Ok(());
    }
    Err(format!(
        "{count} lights, more than the {MAX_LIGHTS} one run evaluates: merge distant lights or use an environment map"
    ))
}

/// Why a lights file was refused. Lights are numbered from 1 in the order of the file.
#[derive(Debug, thiserror::Error)]
pub enum LightsFileError {
    /// The file could not be read (the error names it and why).
    #[error(transparent)]
    Read(#[from] crate::input::InputError),
    /// Not TOML, or not a list of `[[light]]` tables.
    #[error("{}: {message}", path.display())]
    Syntax {
        /// The file.
        path: PathBuf,
        /// What is wrong, with the line when TOML knows it.
        message: String,
    },
    /// One light is wrong.
    #[error("{}: light {index} ({kind}): {message}", path.display())]
    Light {
        /// The file.
        path: PathBuf,
        /// Its position among the `[[light]]` tables, from 1.
        index: usize,
        /// Its `kind`, or `kind?` when that is what is wrong.
        kind: String,
        /// What is wrong.
        message: String,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SphereTable {
    position: [f64; 3],
    radius: f64,
    radiance: [f64; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PointTable {
    position: [f64; 3],
    intensity: [f64; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DirectionalTable {
    direction: [f64; 3],
    irradiance: [f64; 3],
}

/// Reads a lights file.
pub fn read_lights(path: &Path) -> Result<Vec<Light>, LightsFileError> {
    let text = crate::input::read_input_text(path, crate::input::InputKind::Lights)?;
    parse_lights(&text, path)
}

/// Parses the text of a lights file; `path` names it in errors. At least one light.
pub fn parse_lights(text: &str, path: &Path) -> Result<Vec<Light>, LightsFileError> {
    let syntax = |message: String| LightsFileError::Syntax {
        path: path.to_owned(),
        message,
    };
    let table: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| syntax(crate::text::toml_problem(text, &e)))?;
    if let Some(key) = table.keys().find(|k| *k != "light") {
        return Err(syntax(format!(
            "unknown key `{}`: a lights file holds only [[light]] tables",
            crate::text::excerpt(&crate::text::escape_controls(key))
        )));
    }
    let Some(lights) = table.get("light") else {
        return Err(syntax("no [[light]] tables".into()));
    };
    let toml::Value::Array(lights) = lights else {
        return Err(syntax("`light` must be [[light]] tables".into()));
    };
    if lights.is_empty() {
        return Err(syntax(
            "`light = []` lists no lights: a lights file holds at least one [[light]] table".into(),
        ));
    }
    check_light_count(lights.len()).map_err(syntax)?;
    lights
        .iter()
        .enumerate()
        .map(|(i, value)| {
            let fail = |kind: &str, message: String| LightsFileError::Light {
                path: path.to_owned(),
                index: i + 1,
                kind: kind.to_owned(),
                message,
            };
            let toml::Value::Table(t) = value else {
                return Err(fail("kind?", "not a table".into()));
            };
            light_from_table(t).map_err(|(kind, message)| fail(&kind, message))
        })
        .collect()
}

/// Reads one `[[light]]` table; on error, its kind (or `kind?`) and what is wrong.
pub fn light_from_table(table: &toml::Table) -> Result<Light, (String, String)> {
    let unknown_kind = |m: &str| ("kind?".to_owned(), m.to_owned());
    let kind = match table.get("kind") {
        None => {
            return Err(unknown_kind(
                "missing key `kind` (\"sphere\", \"point\" or \"directional\")",
            ));
        }
        Some(toml::Value::String(k)) => k.clone(),
        Some(other) => {
            return Err(unknown_kind(&format!(
                "`kind` must be a string, not {}",
                other.type_str()
            )));
        }
    };
    let mut fields = table.clone();
    fields.remove("kind");
    let fields = toml::Value::Table(fields);
    let fail = |message: String| (kind.clone(), message);
    // Serde quotes the keys it does not know as written, line breaks included.
    let de = |e: toml::de::Error| {
        fail(crate::text::escape_controls(e.message()).replace("field", "key"))
    };
    let light = match kind.as_str() {
        "sphere" => {
            let t: SphereTable = fields.try_into().map_err(de)?;
            let [radius] = finite_f32s("radius", &[t.radius]).map_err(fail)?;
            if radius <= 0.0 {
                return Err(fail(format!(
                    "`radius` is {radius}: it must be greater than 0"
                )));
            }
            Light::Sphere(SphereLight {
                position: finite_f32s("position", &t.position).map_err(fail)?,
                radius,
                radiance: colour("radiance", &t.radiance).map_err(fail)?,
            })
        }
        "point" => {
            let t: PointTable = fields.try_into().map_err(de)?;
            Light::Point(PointLight {
                position: finite_f32s("position", &t.position).map_err(fail)?,
                intensity: colour("intensity", &t.intensity).map_err(fail)?,
            })
        }
        "directional" => {
            let t: DirectionalTable = fields.try_into().map_err(de)?;
            let direction = finite_f32s("direction", &t.direction).map_err(fail)?;
            if direction.iter().all(|&x| x == 0.0) {
                return Err(fail(
                    "`direction` is zero: it points towards the light".into(),
                ));
            }
            Light::Directional(DirectionalLight {
                direction,
                irradiance: colour("irradiance", &t.irradiance).map_err(fail)?,
            })
        }
        other => {
            // Quoted and cut to its first line: `"directi\nal"` printed two lines.
            return Err(unknown_kind(&format!(
                "unknown kind {:?} (expected \"sphere\", \"point\" or \"directional\")",
                crate::text::excerpt(other)
            )));
        }
    };
    // The core's own check, which must agree with the ones above.
    light.validate().map_err(|e| fail(e.to_string()))?;
    Ok(light)
}

/// `values` in f32, the precision lighting is computed in: each must be finite there (1e300
/// is a finite f64 and an infinite f32).
pub fn finite_f32s<const N: usize>(key: &str, values: &[f64; N]) -> Result<[f32; N], String> {
    match values.iter().find(|&&x| !(x as f32).is_finite()) {
        Some(x) => Err(format!(
            "`{key}` holds {x:?}: every value must be a finite f32 (magnitude up to {:e})",
            f32::MAX
        )),
        None => Ok(values.map(|x| x as f32)),
    }
}

/// A colour: finite in f32 and not negative.
fn colour(key: &str, values: &[f64; 3]) -> Result<[f32; 3], String> {
    let rgb = finite_f32s(key, values)?;
    match rgb.iter().find(|&&x| x < 0.0) {
        Some(x) => Err(format!("`{key}` holds {x}: colours must not be negative")),
        None => Ok(rgb),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        parse_lights(text, Path::new("l.toml"))
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn reads_the_three_kinds() {
        let text = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/lights/three-lights.toml"),
        )
        .unwrap();
        let lights = parse_lights(&text, Path::new("three-lights.toml")).unwrap();
        assert_eq!(lights.len(), 3);
        assert_eq!(
            lights[0],
            Light::Sphere(SphereLight {
                position: [0.0, 1.2, 0.8],
                radius: 0.1,
                radiance: [4.0, 3.5, 3.0]
            })
        );
        assert!(matches!(lights[1], Light::Point(_)));
        assert!(matches!(lights[2], Light::Directional(_)));
    }

    #[test]
    fn errors_name_file_light_kind_and_problem() {
        let sphere = "[[light]]\nkind = \"sphere\"\nposition = [0, 0, 1]\n";
        for (text, fragments) in [
            (
                format!("{sphere}radius = 1\nradiance = [1, 1, 1]\nradus = 2\n"),
                &["l.toml", "light 1 (sphere)", "unknown key `radus`"][..],
            ),
            (
                format!("{sphere}radiance = [1, 1, 1]\n"),
                &["light 1 (sphere)", "missing key `radius`"],
            ),
            (
                format!("{sphere}radius = -1\nradiance = [1, 1, 1]\n"),
                &["light 1 (sphere)", "`radius` is -1"],
            ),
            (
                format!("{sphere}radius = nan\nradiance = [1, 1, 1]\n"),
                &["`radius` holds NaN", "finite f32"],
            ),
            (
                format!("{sphere}radius = 1\nradiance = [1, 1e300, 1]\n"),
                &["light 1 (sphere)", "`radiance` holds 1e300", "finite f32"],
            ),
            (
                "light = []\n".into(),
                &["l.toml", "`light = []` lists no lights"],
            ),
            (
                format!("{sphere}radius = 1\nradiance = [1, -1, 1]\n"),
                &["`radiance` holds -1"],
            ),
            (
                "[[light]]\nkind = \"spot\"\n".into(),
                &["light 1 (kind?)", "unknown kind \"spot\""],
            ),
            (
                format!(
                    "{sphere}radius = 1\nradiance = [1, 1, 1]\n[[light]]\nkind = \"directional\"\ndirection = [0, 0, 0]\nirradiance = [1, 1, 1]\n"
                ),
                &["light 2 (directional)", "`direction` is zero"],
            ),
            (
                "[[light]]\nposition = [0, 0, 0]\n".into(),
                &["light 1 (kind?)", "missing key `kind`"],
            ),
            ("lights = 1\n".into(), &["unknown key `lights`"]),
            // Keys and kinds holding a line break stay on the error's one line.
            ("\"a\\nb\" = 1\n".into(), &["unknown key `a\\nb`"]),
            (
                format!("{sphere}radius = 1\nradiance = [1, 1, 1]\n\"r\\n\" = 2\n"),
                &["light 1 (sphere)", "unknown key `r\\n`"],
            ),
            (
                "[[light]]\nkind = \"spot\\nlight\"\n".into(),
                &["light 1 (kind?)", "unknown kind \"spot…\""],
            ),
            ("".into(), &["no [[light]] tables"]),
            ("[[light]\n".into(), &["l.toml", "line 1"]),
        ] {
            let e = err(&text);
            assert!(!e.contains('\n'), "{e:?}");
            for f in fragments {
                assert!(e.contains(f), "{f:?} missing from {e:?}");
            }
        }
    }
}
