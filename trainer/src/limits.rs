//! The limits one run holds to, shared by the stages that check them: a character's extent
//! (the readers refuse what the tracer could not hit exactly), frames (the readers refuse
//! clips longer than a bake or an evaluation takes), bytes and rays per vertex.

/// Most frames one run bakes or evaluates: 83 s of 120 fps capture, 5.5 min at 30 fps. At the
/// bake's measured 0.1–1 s per pose that is up to about three hours, and as many checkpoint
/// files.
pub const MAX_FRAMES: usize = 10_000;
/// Most bytes of posed meshes, transfer and ray hits one run may hold: a sixth of this
/// machine's 24 GB, since the fit needs more on top and the machine is shared.
pub const MAX_BYTES: u64 = 4_000_000_000;
/// Largest accepted `max |coordinate| + bounding-box diagonal`: far beyond any character in
/// any unit, and small enough that the triple products inside the ray–triangle test (cubes of
/// coordinates, at most ~1e36 here) stay below `f32::MAX` (3.4e38) instead of overflowing
/// into infinities that would silently turn occluders into misses.
pub const MAX_EXTENT: f64 = 1e12;
/// Upper bound on rays per vertex: 65 536 already puts QMC error far below f32 resolution of
/// the transfer, and bounce bakes store one hit per occluded ray.
pub const MAX_RAYS: usize = 1 << 16;
