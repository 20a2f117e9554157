//! The crate's WGSL, compiled into the binary. Every kernel is listed in [`ALL`], so the tests
//! validate each one with naga on a machine without any GPU, and an engine can build its own
//! pipelines from the same source (the WGSL is the reference for ports).

/// One WGSL file of this crate.
#[derive(Clone, Copy, Debug)]
pub struct Shader {
    /// Its file name under `src/shaders/`, for labels and error messages.
    pub name: &'static str,
    /// The WGSL source.
    pub source: &'static str,
}

/// The vertex rows as aprt-core stores them and how a kernel reads one value (`row_value`),
/// a vertex's bone (`vertex_bone`) and its own index (`invocation`); the kernels below are
/// this file followed by their own.
pub const ROWS: Shader = Shader {
    name: "rows.wgsl",
    source: include_str!("rows.wgsl"),
};

/// Per-vertex shading from the lighting weights (entry point `shade`); see
/// [`GpuModel::shade`](crate::GpuModel::shade).
pub const SHADE: Shader = Shader {
    name: "shade.wgsl",
    source: concat!(include_str!("rows.wgsl"), include_str!("shade.wgsl")),
};

/// This frame's transfer weights and a vertex's transfer from them (`transfer_value`), for
/// the kernels that need the transfer.
pub const WEIGHTS: Shader = Shader {
    name: "weights.wgsl",
    source: concat!(include_str!("rows.wgsl"), include_str!("weights.wgsl")),
};

/// Per-vertex transfer from the transfer weights (entry point `transfer_values`); see
/// [`GpuModel::transfer`](crate::GpuModel::transfer).
pub const TRANSFER: Shader = Shader {
    name: "transfer.wgsl",
    source: concat!(
        include_str!("rows.wgsl"),
        include_str!("weights.wgsl"),
        include_str!("transfer.wgsl")
    ),
};

/// The real SH basis up to order 6 as aprt-core evaluates it (`sh_basis`), for the kernels
/// that turn directions into coefficients.
pub const SH: Shader = Shader {
    name: "sh.wgsl",
    source: include_str!("sh.wgsl"),
};

/// The occluder proxies' correction of shading and transfer (entry points `occlude_shading`
/// and `occlude_transfer`); see [`GpuModel::occlude`](crate::GpuModel::occlude).
pub const OCCLUDE: Shader = Shader {
    name: "occlude.wgsl",
    source: concat!(
        include_str!("rows.wgsl"),
        include_str!("sh.wgsl"),
        include_str!("occlude.wgsl")
    ),
};

/// Per-vertex lights through each vertex's transfer (entry point `shade_lights`); see
/// [`GpuModel::shade_lights`](crate::GpuModel::shade_lights).
pub const LIGHTS: Shader = Shader {
    name: "lights.wgsl",
    source: concat!(
        include_str!("rows.wgsl"),
        include_str!("sh.wgsl"),
        include_str!("weights.wgsl"),
        include_str!("lights.wgsl")
    ),
};

/// Shading under an irradiance rig's lighting at each vertex's position (entry point
/// `shade_rig`); see [`GpuModel::shade_rig`](crate::GpuModel::shade_rig).
pub const RIG: Shader = Shader {
    name: "rig.wgsl",
    source: concat!(include_str!("rows.wgsl"), include_str!("rig.wgsl")),
};

/// Every shader of the crate.
pub const ALL: &[Shader] = &[ROWS, WEIGHTS, SHADE, TRANSFER, SH, OCCLUDE, LIGHTS, RIG];
