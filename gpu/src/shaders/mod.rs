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

/// Widens packed f16 pairs and scaled i8 quads to f32 (entry point `main`); see
/// [`unpack`](crate::unpack).
pub const UNPACK: Shader = Shader {
    name: "unpack.wgsl",
    source: include_str!("unpack.wgsl"),
};

/// Every shader of the crate.
pub const ALL: &[Shader] = &[UNPACK];
