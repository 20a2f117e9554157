//! One loaded model and its per-frame state: what the exports drive, written in safe Rust
//! so the host can test it against the core's own calls.

use aprt_core::{Error, LitWeights, Model, ModelInfo, PoseWeights, Rotation, ShError};

/// The largest blob the page can load (16 MiB of linear memory, zero until written, so it
/// costs no `.wasm` bytes).
pub const BLOB_CAPACITY: usize = 16 << 20;

/// The most vertices one [`Session::shade`] fills (262,144: a 1 MiB shading buffer).
pub const MAX_SHADED: usize = 1 << 18;

/// A validated model and the caller-owned state of its frames (about 80 KiB, so it lives in
/// a `static` on wasm32).
pub struct Session<'a> {
    model: Model<'a>,
    pose: PoseWeights,
    lit: LitWeights,
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
        })
    }

    /// The model's dimensions.
    pub fn info(&self) -> &ModelInfo {
        self.model.info()
    }

    /// One frame: `set_pose(angles)`, `light(lighting, bones)`, then the shading of every
    /// vertex into `shading[..vertices]`. Exactly the core's three calls, nothing more, so
    /// the page's timing of this is the model's cost per frame.
    pub fn shade(
        &mut self,
        angles: &[f32],
        lighting: &[f32],
        bones: &[Rotation],
        shading: &mut [f32],
    ) -> Result<(), Error> {
        let info = *self.model.info();
        self.model.set_pose(angles, &mut self.pose)?;
        self.model
            .light(&self.pose, lighting, bones, &mut self.lit)?;
        let out = shading
            .get_mut(..info.vertices())
            .ok_or(Error::BufferTooSmall {
                needed: info.vertices() * 4,
            })?;
        self.model.shade(&self.lit, 0, out)
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

    const BONES: &[u8] = include_bytes!("../../../fixtures/golden/v1-bones.aprt");

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
