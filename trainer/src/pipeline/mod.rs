//! The runs that drive the stages below: pose, bake (through checkpoints and shards), fit the
//! irradiance rig and the model, choose the precision and write the blob (`train.rs`, `aprt
//! train`), and the same under a scene's plan with the full simulation timed beside it
//! (`scene.rs`, `aprt train --scene`). bake/, lighting/, irradiance_rig/ and model/ each offer
//! one step; only this stage calls them in order.

pub mod scene;
pub mod scene_light_map;
pub mod train;
