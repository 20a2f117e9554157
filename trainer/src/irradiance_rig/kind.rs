//! The irradiance-rig kinds users name on the command line: `constant`, `gradient`,
//! `lattice:NXxNYxNZ` and `mixed:x=KIND,y=KIND,z=KIND` (KIND one of `constant`, `gradient`,
//! `latticeN`), over the axes of the character's own frame.

use std::fmt;
use std::str::FromStr;

use aprt_core::{AxisKind, MAX_LATTICE, MAX_RIG_VECTORS, RigShape};

/// A rig kind: its shape, and whether it is the paper's centroid rig (one probe at the centre,
/// as engines light a skinned mesh) rather than a shape fitted to the surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RigKind {
    /// The basis functions.
    pub shape: RigShape,
    /// `constant`: the lighting at the centre of the character's box, unfitted.
    pub centroid: bool,
}

/// Why a rig kind did not parse.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "rig kind {given:?}: {problem} (kinds: constant, gradient, lattice:NXxNYxNZ, \
     mixed:x=KIND,y=KIND,z=KIND with KIND constant, gradient or latticeN; N in 1..={MAX_LATTICE})"
)]
pub struct RigKindError {
    /// What was given.
    pub given: String,
    /// What is wrong with it.
    pub problem: String,
}

/// A lattice axis of `n` nodes; one node is a constant axis.
fn lattice(n: &str) -> Result<AxisKind, String> {
    match n.parse::<usize>() {
        Ok(1) => Ok(AxisKind::Constant),
        Ok(n @ 2..=MAX_LATTICE) => Ok(AxisKind::Lattice(n as u8)),
        _ => Err(format!("{n:?} is not a node count in 1..={MAX_LATTICE}")),
    }
}

fn axis(kind: &str) -> Result<AxisKind, String> {
    match kind {
        "constant" => Ok(AxisKind::Constant),
        "gradient" => Ok(AxisKind::Linear),
        other => match other.strip_prefix("lattice") {
            Some(n) => lattice(n),
            None => Err(format!(
                "axis kind {other:?} is not constant, gradient or latticeN"
            )),
        },
    }
}

fn axis_name(kind: AxisKind) -> String {
    match kind {
        AxisKind::Constant => "constant".into(),
        AxisKind::Linear => "gradient".into(),
        AxisKind::Lattice(n) => format!("lattice{n}"),
    }
}

fn parse_mixed(spec: &str) -> Result<[AxisKind; 3], String> {
    let mut axes = [None; 3];
    for part in spec.split(',') {
        let (name, kind) = part
            .split_once('=')
            .ok_or_else(|| format!("{part:?} is not AXIS=KIND"))?;
        let slot = match name.trim() {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            other => return Err(format!("axis {other:?} is not x, y or z")),
        };
        if axes[slot].replace(axis(kind.trim())?).is_some() {
            return Err(format!("axis {} given twice", name.trim()));
        }
    }
    let names = ["x", "y", "z"];
    let mut out = [AxisKind::Constant; 3];
    for (i, a) in axes.iter().enumerate() {
        out[i] = a.ok_or_else(|| format!("axis {} missing", names[i]))?;
    }
    Ok(out)
}

impl RigKind {
    /// The kind of a stored rig, as `--rig` spells it back.
    pub fn of(rig: &aprt_core::IrradianceRig<'_>) -> RigKind {
        RigKind {
            shape: rig.shape(),
            // A constant rig of one sample is the centroid probe; fitted ones have many.
            centroid: rig.vectors() == 1 && rig.samples() == 1,
        }
    }
}

impl FromStr for RigKind {
    type Err = RigKindError;

    fn from_str(given: &str) -> Result<RigKind, RigKindError> {
        let fail = |problem: String| RigKindError {
            given: given.into(),
            problem,
        };
        let fitted = |shape: RigShape| RigKind {
            shape,
            centroid: false,
        };
        let kind = match given.trim() {
            "constant" => RigKind {
                shape: RigShape::Product([AxisKind::Constant; 3]),
                centroid: true,
            },
            "gradient" => fitted(RigShape::Gradient),
            other => {
                if let Some(dims) = other.strip_prefix("lattice:") {
                    let parts: Vec<&str> = dims.split('x').collect();
                    let [x, y, z] = parts[..] else {
                        return Err(fail(format!("{dims:?} is not NXxNYxNZ")));
                    };
                    fitted(RigShape::Product([
                        lattice(x).map_err(fail)?,
                        lattice(y).map_err(fail)?,
                        lattice(z).map_err(fail)?,
                    ]))
                } else if let Some(spec) = other.strip_prefix("mixed:") {
                    fitted(RigShape::Product(parse_mixed(spec).map_err(fail)?))
                } else {
                    return Err(fail("unknown kind".into()));
                }
            }
        };
        if kind.shape.vectors() > MAX_RIG_VECTORS {
            return Err(fail(format!(
                "{} SH vectors, at most {MAX_RIG_VECTORS}",
                kind.shape.vectors()
            )));
        }
        Ok(kind)
    }
}

/// The canonical spelling, which parses back to the same kind.
impl fmt::Display for RigKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.shape {
            _ if self.centroid => f.write_str("constant"),
            RigShape::Gradient => f.write_str("gradient"),
            RigShape::Product(axes) => {
                if let [
                    AxisKind::Lattice(x),
                    AxisKind::Lattice(y),
                    AxisKind::Lattice(z),
                ] = axes
                {
                    return write!(f, "lattice:{x}x{y}x{z}");
                }
                let [x, y, z] = axes.map(axis_name);
                write!(f, "mixed:x={x},y={y},z={z}")
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_parse_and_print_back() {
        for (text, vectors) in [
            ("constant", 1),
            ("gradient", 4),
            ("lattice:2x2x3", 12),
            ("lattice:8x4x2", 64),
            ("mixed:x=lattice3,y=gradient,z=constant", 6),
            ("mixed:x=constant,y=constant,z=constant", 1),
        ] {
            let kind: RigKind = text.parse().unwrap();
            assert_eq!(kind.shape.vectors(), vectors, "{text}");
            assert_eq!(kind.to_string(), text);
        }
        // Axes in any order, one-node lattices are constant.
        let car: RigKind = "mixed:z=constant, y=gradient, x=lattice3".parse().unwrap();
        assert_eq!(car.to_string(), "mixed:x=lattice3,y=gradient,z=constant");
        let flat: RigKind = "lattice:3x1x1".parse().unwrap();
        assert_eq!(flat.to_string(), "mixed:x=lattice3,y=constant,z=constant");
    }

    #[test]
    fn bad_kinds_say_what_is_wrong() {
        for (text, problem) in [
            ("cubic", "unknown kind"),
            ("lattice:2x2", "is not NXxNYxNZ"),
            ("lattice:2x0x2", "not a node count"),
            ("lattice:17x2x2", "not a node count"),
            ("lattice:16x16x2", "at most 256"),
            ("mixed:x=lattice3,y=gradient", "axis z missing"),
            ("mixed:x=lattice3,x=gradient,z=constant", "given twice"),
            (
                "mixed:x=spline,y=gradient,z=constant",
                "is not constant, gradient",
            ),
            ("mixed:w=constant", "axis \"w\""),
        ] {
            let err = text.parse::<RigKind>().unwrap_err().to_string();
            assert!(err.contains(problem), "{text}: {err}");
        }
    }
}
