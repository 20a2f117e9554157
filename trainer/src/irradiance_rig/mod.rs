//! Irradiance rigs (*Irradiance Rigs*, Yuan, Nowrouzezahrai and Sloan) in the trainer: the
//! kinds (`kind.rs`), surface samples spread by Lloyd relaxation (`surface_samples.rs`), the
//! least-squares fit of a rig to a character's poses (`fit.rs`), and its accuracy against exact
//! lighting with the error table of section 3.1 (`accuracy.rs`, `aprt irradiance-rig`). The
//! runtime side (`IrradianceRig`) is aprt-core's `irradiance_rig/`.

pub mod accuracy;
pub mod fit;
pub mod kind;
pub mod surface_samples;

pub use accuracy::{RigErrors, RigEvaluation, RigSettings, evaluate_rig, rig_errors};
pub use fit::{FittedRig, GreyError, fit_rig, rig_vectors};
pub use kind::{RigKind, RigKindError};
