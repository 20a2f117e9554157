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
    position: [f32; 3],
    radius: f32,
    radiance: [f32; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PointTable {
    position: [f32; 3],
    intensity: [f32; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DirectionalTable {
    direction: [f32; 3],
    irradiance: [f32; 3],
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
        .map_err(|e: toml::de::Error| syntax(crate::io::toml_problem(text, &e)))?;
    if let Some(key) = table.keys().find(|k| *k != "light") {
        return Err(syntax(format!(
            "unknown key `{key}`: a lights file holds only [[light]] tables"
        )));
    }
    let Some(lights) = table.get("light") else {
        return Err(syntax("no [[light]] tables".into()));
    };
    let toml::Value::Array(lights) = lights else {
        return Err(syntax("`light` must be [[light]] tables".into()));
    };
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
    let de = |e: toml::de::Error| fail(e.message().replace("field", "key"));
    let light = match kind.as_str() {
        "sphere" => {
            let t: SphereTable = fields.try_into().map_err(de)?;
            finite("position", &t.position).map_err(fail)?;
            finite("radius", &[t.radius]).map_err(fail)?;
            if t.radius <= 0.0 {
                return Err(fail(format!(
                    "`radius` is {}: it must be greater than 0",
                    t.radius
                )));
            }
            colour("radiance", &t.radiance).map_err(fail)?;
            Light::Sphere(SphereLight {
                position: t.position,
                radius: t.radius,
                radiance: t.radiance,
            })
        }
        "point" => {
            let t: PointTable = fields.try_into().map_err(de)?;
            finite("position", &t.position).map_err(fail)?;
            colour("intensity", &t.intensity).map_err(fail)?;
            Light::Point(PointLight {
                position: t.position,
                intensity: t.intensity,
            })
        }
        "directional" => {
            let t: DirectionalTable = fields.try_into().map_err(de)?;
            finite("direction", &t.direction).map_err(fail)?;
            if t.direction.iter().all(|&x| x == 0.0) {
                return Err(fail(
                    "`direction` is zero: it points towards the light".into(),
                ));
            }
            colour("irradiance", &t.irradiance).map_err(fail)?;
            Light::Directional(DirectionalLight {
                direction: t.direction,
                irradiance: t.irradiance,
            })
        }
        other => {
            return Err(unknown_kind(&format!(
                "unknown kind \"{other}\" (expected \"sphere\", \"point\" or \"directional\")"
            )));
        }
    };
    // The core's own check, which must agree with the ones above.
    light.validate().map_err(|e| fail(e.to_string()))?;
    Ok(light)
}

fn finite(key: &str, values: &[f32]) -> Result<(), String> {
    match values.iter().find(|x| !x.is_finite()) {
        Some(x) => Err(format!("`{key}` holds {x}: every value must be finite")),
        None => Ok(()),
    }
}

fn colour(key: &str, values: &[f32; 3]) -> Result<(), String> {
    finite(key, values)?;
    match values.iter().find(|&&x| x < 0.0) {
        Some(x) => Err(format!("`{key}` holds {x}: colours must not be negative")),
        None => Ok(()),
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
                &["`radius` holds NaN"],
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
            ("".into(), &["no [[light]] tables"]),
            ("[[light]\n".into(), &["l.toml", "line 1"]),
        ] {
            let e = err(&text);
            for f in fragments {
                assert!(e.contains(f), "{f:?} missing from {e:?}");
            }
        }
    }
}
