//! One loaded model and its per-frame state: what the exports drive, written in safe Rust
//! so the host can test it against the core's own calls.

use aprt_core::{
    Error, LitWeights, Model, ModelInfo, PoseWeights, ProxyFrame, Rotation, ShError, Skinning,
};

/// Where a model's vertex rows lie in its blob and how they are laid out
/// ([`aprt_core::VertexRows`]), for a device that runs the shading loop itself: `web/webgpu.js`
/// reads these nine u32, in this order, into the `Rows` block of aprt-gpu's `rows.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RowsLayout {
    /// Byte offset of the rows section in the blob.
    pub offset: u32,
    /// Its length in bytes (whole 32-bit words).
    pub len: u32,
    /// The blob's encoding tag, which `rows.wgsl` numbers alike: 0 f32, 1 f16, 2 i8.
    pub encoding: u32,
    /// Rows of bone indices per block: 1 for a bone-frame model, else 0.
    pub lead_rows: u32,
    /// Rows of values per block.
    pub row_width: u32,
    /// Blocks of eight vertices.
    pub blocks: u32,
    /// Bones, at least 1: the lighting weights hold `row_width` values per bone.
    pub bones: u32,
    /// SH coefficients n².
    pub coeffs: u32,
    /// Lighting weights [`Session::light`] returns (`bones · row_width`).
    pub lit_len: u32,
}

/// The largest blob the page can load (16 MiB of linear memory, zero until written, so it
/// costs no `.wasm` bytes).
pub const BLOB_CAPACITY: usize = 16 << 20;

/// The most vertices one [`Session::shade`] fills (262,144: a 1 MiB shading buffer).
pub const MAX_SHADED: usize = 1 << 18;

/// A validated model and the caller-owned state of its frames (about 84 KiB, so it lives in
/// a `static` on wasm32).
pub struct Session<'a> {
    model: Model<'a>,
    pose: PoseWeights,
    lit: LitWeights,
    proxies: ProxyFrame,
}

impl<'a> Session<'a> {
    /// Validates `blob` once ([`Model::parse`]) and refuses a model with more vertices than
    /// the shading buffer holds.
    pub fn open(blob: &'a [u8]) -> Result<Session<'a>, Error> {
        let model = Model::parse(blob)?;
        let vertices = model.info().vertices();
        if vertices > MAX_SHADED {
            // The shading buffer would need this many bytes.
            return Err(Error::BufferTooSmall {
                needed: vertices * 4,
            });
        }
        Ok(Session {
            model,
            pose: PoseWeights::new(),
            lit: LitWeights::new(),
            proxies: ProxyFrame::new(),
        })
    }

    /// The model's dimensions.
    pub fn info(&self) -> &ModelInfo {
        self.model.info()
    }

    /// Where the vertex rows lie in the blob and their layout, for a device that shades them
    /// itself from [`Session::light`]'s weights. Every figure fits a u32: the blob is at most
    /// [`BLOB_CAPACITY`] bytes.
    pub fn rows_layout(&self) -> RowsLayout {
        let info = self.model.info();
        let rows = self.model.vertex_rows();
        RowsLayout {
            // The rows are a slice of the blob (`Model::vertex_rows`): their distance from its
            // start is their offset in it.
            offset: (rows.bytes.as_ptr() as usize - self.model.blob().as_ptr() as usize) as u32,
            len: rows.bytes.len() as u32,
            encoding: rows.encoding as u32,
            lead_rows: rows.lead_rows as u32,
            row_width: rows.row_width as u32,
            blocks: rows.blocks as u32,
            bones: info.bones().max(1) as u32,
            coeffs: info.coeffs() as u32,
            lit_len: info.lit_weights_len() as u32,
        }
    }

    /// A frame's pose and lighting: `set_pose(angles)`, `light(lighting, bones)`, the core's
    /// first two calls of [`Session::shade`]. Returns the lighting weights
    /// ([`ModelInfo::lit_values`]) for a device that runs the loop over the vertices itself.
    pub fn light(
        &mut self,
        angles: &[f32],
        lighting: &[f32],
        bones: &[Rotation],
    ) -> Result<&[f32], Error> {
        self.model.set_pose(angles, &mut self.pose)?;
        self.model
            .light(&self.pose, lighting, bones, &mut self.lit)?;
        self.model.info().lit_values(&self.lit)
    }

    /// One frame: `set_pose(angles)`, `light(lighting, bones)`, then the shading of every
    /// vertex into `shading[..vertices]`. Exactly the core's three calls, nothing more, so
    /// the page's timing of this is the shading's cost per frame (a model with occluder
    /// proxies adds [`Session::occlude`]'s).
    pub fn shade(
        &mut self,
        angles: &[f32],
        lighting: &[f32],
        bones: &[Rotation],
        shading: &mut [f32],
    ) -> Result<(), Error> {
        let info = *self.model.info();
        self.light(angles, lighting, bones)?;
        let out = shading
            .get_mut(..info.vertices())
            .ok_or(Error::BufferTooSmall {
                needed: info.vertices() * 4,
            })?;
        self.model.shade(&self.lit, 0, out)
    }

    /// A model with occluder proxies, after [`Session::shade`]: poses them by the bones'
    /// `skinning` matrices and subtracts what they block under `lighting` (the same as
    /// `shade`'s) from `shading`. `positions` and `normals` (one per vertex) are the posed
    /// mesh, skinned exactly as the trainer skins it, or the shading is not `aprt eval`'s.
    /// The core's two calls, nothing more.
    pub fn occlude(
        &mut self,
        skinning: &[Skinning],
        lighting: &[f32],
        (positions, normals): (&[[f32; 3]], &[[f32; 3]]),
        shading: &mut [f32],
    ) -> Result<(), Error> {
        let vertices = self.model.info().vertices();
        self.model.pose_proxies(skinning, &mut self.proxies)?;
        let out = shading.get_mut(..vertices).ok_or(Error::BufferTooSmall {
            needed: vertices * 4,
        })?;
        self.model
            .occlude(&self.proxies, lighting, positions, normals, 0, out)
    }
}

/// Adds a directional light of `strength` from `dir` (need not be unit length) to the SH
/// `lighting` of `order` (`order²` values): the light the user drags, over the environment.
pub fn add_directional(
    order: usize,
    dir: [f32; 3],
    strength: f32,
    lighting: &mut [f32],
) -> Result<(), ShError> {
    let mut light = [0.0; aprt_core::MAX_COEFFS];
    let n2 = order * order;
    let light = light.get_mut(..n2).ok_or(ShError::OutputTooSmall)?;
    aprt_core::project_directional(order, dir, strength, light)?;
    let lighting = lighting.get_mut(..n2).ok_or(ShError::OutputTooSmall)?;
    for (l, d) in lighting.iter_mut().zip(light.iter()) {
        *l += d;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::boxed::Box;
    use std::vec;
    use std::vec::Vec;

    const BONES: &[u8] = include_bytes!("../../../fixtures/golden/v1-bones.aprt");
    const PROXIES: &[u8] = include_bytes!("../../../fixtures/golden/v1-proxies.aprt");
    const STILL: Skinning = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];

    /// The session's frame is the core's three calls: same inputs, same bits.
    #[test]
    fn a_frame_is_the_cores_three_calls() {
        let mut session = Box::new(Session::open(BONES).unwrap());
        let info = *session.info();
        let angles = vec![0.2; info.pose_len()];
        let mut lighting = vec![0.5; info.coeffs()];
        add_directional(info.order(), [0.3, -0.5, 0.8], 2.0, &mut lighting).unwrap();
        let turn = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
        let bones = vec![turn; info.bones()];
        let mut shading = vec![0.0; info.vertices() + 3];
        session
            .shade(&angles, &lighting, &bones, &mut shading)
            .unwrap();

        let model = Model::parse(BONES).unwrap();
        let (mut pose, mut lit) = (Box::new(PoseWeights::new()), Box::new(LitWeights::new()));
        model.set_pose(&angles, &mut pose).unwrap();
        model.light(&pose, &lighting, &bones, &mut lit).unwrap();
        let mut expected = vec![0.0; info.vertices()];
        model.shade(&lit, 0, &mut expected).unwrap();
        assert_eq!(shading[..info.vertices()], expected[..]);
        assert_eq!(shading[info.vertices()..], [0.0; 3]);
    }

    /// A device's view of the model: the layout names the core's vertex rows in the blob, and
    /// `light` gives the core's lighting weights, which the rows turn into `shade`'s values.
    #[test]
    fn the_rows_layout_and_light_are_the_cores() {
        const WORLD: &[u8] = include_bytes!("../../../fixtures/golden/v1-world.aprt");
        for blob in [BONES, WORLD] {
            let mut session = Box::new(Session::open(blob).unwrap());
            let info = *session.info();
            let model = Model::parse(blob).unwrap();
            let rows = model.vertex_rows();
            let layout = session.rows_layout();
            let (offset, len) = (layout.offset as usize, layout.len as usize);
            assert_eq!(&blob[offset..offset + len], rows.bytes);
            assert_eq!(
                [layout.encoding, layout.lead_rows, layout.row_width],
                [
                    rows.encoding as u32,
                    rows.lead_rows as u32,
                    rows.row_width as u32
                ]
            );
            assert_eq!(layout.blocks as usize, rows.blocks);
            assert_eq!(layout.bones as usize, info.bones().max(1));
            assert_eq!(layout.coeffs as usize, info.coeffs());

            let angles = vec![0.2; info.pose_len()];
            let lighting = vec![0.5; info.coeffs()];
            let turn = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
            let bones = vec![turn; info.bones()];
            let q = session.light(&angles, &lighting, &bones).unwrap().to_vec();
            assert_eq!(q.len(), layout.lit_len as usize);
            let (mut pose, mut lit) = (Box::new(PoseWeights::new()), Box::new(LitWeights::new()));
            model.set_pose(&angles, &mut pose).unwrap();
            model.light(&pose, &lighting, &bones, &mut lit).unwrap();
            assert_eq!(q, info.lit_values(&lit).unwrap());
        }
    }

    /// A frame with proxies is the core's five calls, and the proxies take something off:
    /// the golden model's two spheres hang above bone 1's vertices, which face them.
    #[test]
    fn occlude_is_the_cores_two_calls_after_shade() {
        let mut session = Box::new(Session::open(PROXIES).unwrap());
        let info = *session.info();
        let angles = vec![0.1; info.pose_len()];
        let lighting = [1.0, 0.0, 0.8, 0.0];
        let bones = vec![[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]; info.bones()];
        let skinning = vec![STILL; info.bones()];
        let positions: Vec<[f32; 3]> = (0..info.vertices())
            .map(|j| [0.05 * j as f32 - 0.4, 0.1, 0.0])
            .collect();
        let normals = vec![[0.0, 0.0, 1.0]; info.vertices()];
        let mut shading = vec![0.0; info.vertices()];
        session
            .shade(&angles, &lighting, &bones, &mut shading)
            .unwrap();
        let unoccluded = shading.clone();
        session
            .occlude(&skinning, &lighting, (&positions, &normals), &mut shading)
            .unwrap();

        let model = Model::parse(PROXIES).unwrap();
        let (mut pose, mut lit) = (Box::new(PoseWeights::new()), Box::new(LitWeights::new()));
        let mut frame = Box::new(ProxyFrame::new());
        model.set_pose(&angles, &mut pose).unwrap();
        model.light(&pose, &lighting, &bones, &mut lit).unwrap();
        let mut expected = vec![0.0; info.vertices()];
        model.shade(&lit, 0, &mut expected).unwrap();
        model.pose_proxies(&skinning, &mut frame).unwrap();
        model
            .occlude(&frame, &lighting, &positions, &normals, 0, &mut expected)
            .unwrap();
        assert_eq!(shading, expected);
        assert!(shading.iter().zip(&unoccluded).any(|(s, u)| s < u));
        assert!(shading[..8] == unoccluded[..8], "bone 0 ignores both");
    }

    #[test]
    fn short_buffers_are_errors_not_panics() {
        let mut session = Box::new(Session::open(BONES).unwrap());
        let info = *session.info();
        let bones = vec![[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]; info.bones()];
        let lighting = vec![1.0; info.coeffs()];
        let angles = vec![0.0; info.pose_len()];
        let mut short = vec![0.0; info.vertices() - 1];
        assert!(matches!(
            session.shade(&angles, &lighting, &bones, &mut short),
            Err(Error::BufferTooSmall { .. })
        ));
        assert!(session.shade(&[], &lighting, &bones, &mut short).is_err());
        assert!(add_directional(3, [0.0, 0.0, 1.0], 1.0, &mut [0.0; 4]).is_err());
        assert!(Session::open(&BONES[..100]).is_err());
        let no_proxies = session.occlude(&[STILL; 3], &lighting, (&[], &[]), &mut short);
        assert!(matches!(no_proxies, Err(Error::NoProxies)));

        let mut session = Box::new(Session::open(PROXIES).unwrap());
        let info = *session.info();
        let lighting = vec![1.0; info.coeffs()];
        let mut shading = vec![0.0; info.vertices()];
        let vertices = vec![[0.0, 0.0, 1.0]; info.vertices()];
        let few = &vertices[1..];
        for (skinning, positions, normals) in [
            (&[STILL][..], &vertices[..], &vertices[..]),
            (&[STILL, STILL][..], few, &vertices[..]),
            (&[STILL, STILL][..], &vertices[..], few),
        ] {
            let result = session.occlude(skinning, &lighting, (positions, normals), &mut shading);
            assert!(result.is_err());
        }
        let (ok, short) = ((&vertices[..], &vertices[..]), &mut shading[1..]);
        assert!(session.occlude(&[STILL; 2], &lighting, ok, short).is_err());
    }

    #[test]
    fn a_directional_light_adds_its_projection() {
        let mut lighting = [1.0; 9];
        add_directional(3, [0.0, 0.0, 2.0], 3.0, &mut lighting).unwrap();
        let mut alone = [0.0; 9];
        aprt_core::project_directional(3, [0.0, 0.0, 1.0], 3.0, &mut alone).unwrap();
        for (l, a) in lighting.iter().zip(alone) {
            assert!((l - 1.0 - a).abs() < 1e-6);
        }
    }
}
