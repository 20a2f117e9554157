//! glTF 2.0 characters as a [`Rig`]: the skinned mesh, its skin and its animations, read with
//! the `gltf` crate from `.gltf` (embedded `data:` or external buffers) or `.glb`.
//!
//! Decisions, and why:
//!
//! - **Which mesh.** Every node that has both a mesh and a skin, in node order; they must all
//!   use the same skin (one skeleton, one pose vector), else loading fails naming them. A file
//!   with no such node fails ("without a skin"). Unskinned mesh nodes (props) are ignored.
//!   The nodes' primitives are merged in order, vertices in accessor order, so vertex `i` of
//!   every output is a fixed vertex of the file.
//! - **Primitive modes.** TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN are baked (strips and
//!   fans unrolled); POINTS and LINES* are an error naming the primitive: they have no surface
//!   to shadow, and silently dropping geometry would hide a wrong export.
//! - **Normals.** The file's `NORMAL` when present (renormalised). Otherwise area-weighted
//!   normals over the primitive's own indexing: a non-indexed primitive (Fox.gltf) gets flat
//!   normals, which is what glTF requires of clients when normals are absent and matches that
//!   low-poly model's faceted look; vertices are not welded by position, because welding
//!   would make such a file smooth against the spec, and flat normals for an *indexed*
//!   primitive would need split vertices, breaking the one-vertex-per-accessor-element order.
//! - **Skinning.** Every `JOINTS_n`/`WEIGHTS_n` set is used, weights normalised by
//!   [`Skin::from_influences`]. Joint matrix = `F · world(joint) · inverseBind(joint)`, with
//!   `F` the inverse of the skinned mesh node's rest world matrix (see the `skeleton`
//!   module): glTF ignores the mesh node's transform when skinning, and `F` merely expresses
//!   the world-space result in the frame of the file's vertex data, so the rest pose gives
//!   back the stored mesh. [`GltfRig::up`] says where glTF's world +Y points in that frame.
//! - **Pose vector.** Three numbers per skin joint, in skin order, named `<joint>.x/.y/.z`:
//!   the rotation vector (log map) of `q_rest⁻¹ · q_local`, the joint's local rotation
//!   relative to its rest rotation *in the joint's own rest frame* (`q_local = q_rest · δ`).
//!   The other order, `q_local · q_rest⁻¹`, is the same rotation seen in the parent's frame;
//!   the two vectors differ by a fixed rotation per joint, so the linear fit is unaffected,
//!   but in the joint frame the components follow the rig's own joint axes: a hinge modelled
//!   about its local x moves `.x` only, and constant components can be dropped by name.
//!   Rest = the node's transform in the file, which is the bind pose for the assets tested
//!   (the all-zero pose reproduces the stored mesh). Every joint is present, moving or not.
//!   Along a clip each vector is unwrapped to the turn nearest the previous frame's, so a
//!   joint turning on through a half turn stays continuous instead of jumping from π to −π.
//! - **Translations and scales.** The pose vector carries rotations only: joint translations
//!   and scales, and every property of non-joint ancestors, stay at their rest values when
//!   posing. Animated ones are listed by [`GltfRig::held_channels`] with how far they stray
//!   from rest. A translated skeleton root (root motion, hip bob) moves the whole mesh
//!   rigidly, which PRT transfer does not depend on; other held channels are a limitation.
//!   [`GltfRig::animated_joint_matrices`] poses with every channel, for measuring it.
//! - **Clips.** One per animation, named by its glTF name (`animation<i>` when unnamed,
//!   `<name>#<i>` when a name repeats), sampled at `fps` at `t = i/fps` from 0 up to and
//!   including the animation's end: the last frame is clamped to exactly the end time, so it
//!   may be closer to the previous frame than `1/fps`. Interpolation follows glTF (see
//!   [`curve`]). Morph-target weights are not applied.

mod animation;
pub mod curve;
mod document;
mod load;
mod skeleton;
mod spec;

use crate::rig::uv::UvLayout;
pub(crate) use document::{external_file, split as gltf_split};
use std::path::{Path, PathBuf};

use glam::{DVec3, Mat4, Vec3};

use crate::limits::MAX_FRAMES;
use crate::rig::mesh::Mesh;
use crate::rig::skin::{Skin, SkinError};
use crate::rig::{Clip, PoseError, Rig, RigError, check_fps, check_pose};
use animation::Animation;
use skeleton::{Skeleton, Trs};

/// `kind index "name"`, the way every error names an item.
pub fn item(kind: &str, index: usize, name: Option<&str>) -> String {
    match name {
        Some(name) => format!("{kind} {index} {}", crate::text::quote(name)),
        None => format!("{kind} {index}"),
    }
}

/// Why a glTF rig could not be loaded, posed or sampled. Load errors name the file and the
/// item (mesh, primitive, accessor, node, skin, animation channel) and what is wrong with it.
#[derive(Debug, thiserror::Error)]
pub enum GltfError {
    /// The file could not be read (the error names it).
    #[error(transparent)]
    Read(#[from] crate::input::InputError),
    /// The external file of a buffer could not be read.
    #[error("{path}: {buffer}: {source}", path = path.display())]
    Buffer {
        /// The glTF file.
        path: PathBuf,
        /// The buffer, e.g. `buffer 0 "mesh"`.
        buffer: String,
        /// Why its file (named in the error) could not be read.
        source: crate::input::InputError,
    },
    /// The bytes are not a glTF document: empty, truncated GLB, JSON that does not parse.
    #[error("{path}: {problem}", path = path.display())]
    Malformed {
        /// The file.
        path: PathBuf,
        /// What is wrong, with the byte, line or column where known.
        problem: String,
    },
    /// No node has both a mesh and a skin.
    #[error("{path}: glTF without a skin: no node has both a mesh and a skin, so it cannot be posed", path = path.display())]
    NoSkin {
        /// The file.
        path: PathBuf,
    },
    /// Skinned mesh nodes use different skins.
    #[error("{path}: skinned mesh nodes must share one skin, but {nodes}", path = path.display())]
    SkinsDiffer {
        /// The file.
        path: PathBuf,
        /// Each skinned mesh node and its skin.
        nodes: String,
    },
    /// An item of the file is malformed or unsupported.
    #[error("{path}: {item}: {problem}", path = path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// The item, e.g. `mesh 0 "body" primitive 1` or `animation 2 "Run" channel 4`.
        item: String,
        /// What is wrong.
        problem: String,
    },
    /// The merged skin weights are invalid (vertex index in merged order).
    #[error("{path}: skin weights", path = path.display())]
    Skin {
        /// The file.
        path: PathBuf,
        /// The skin error.
        source: SkinError,
    },
    /// The sampling rate is not a positive finite number.
    #[error("frame rate {fps} is not a positive finite number")]
    Fps {
        /// The rate given.
        fps: f64,
    },
    /// A pose that cannot pose the rig.
    #[error("{}", path.display())]
    Pose {
        /// The file.
        path: PathBuf,
        /// What is wrong with the pose.
        #[source]
        source: PoseError,
    },
    /// The file has no animations, so there is no clip to sample.
    #[error("{path}: the file has no animations, so it has no clip to pose the character with", path = path.display())]
    NoAnimations {
        /// The file.
        path: PathBuf,
    },
    /// No clip has the requested name.
    #[error("{path}: no clip named {}; available: {available}", crate::text::quote(.name), path = path.display())]
    UnknownClip {
        /// The file.
        path: PathBuf,
        /// The name asked for.
        name: String,
        /// Comma-separated clip names.
        available: String,
    },
    /// A clip would have too many frames, or a frame index is past its end.
    #[error("{path}: clip {}: {problem}", crate::text::quote(.clip), path = path.display())]
    Frames {
        /// The file.
        path: PathBuf,
        /// The clip.
        clip: String,
        /// What is wrong.
        problem: String,
    },
}

/// An animated property the pose vector does not carry: it is held at its rest value when a
/// pose is applied. Lets a report say what the rig leaves out and by how much.
#[derive(Clone, Debug, PartialEq)]
pub struct HeldChannel {
    /// Clip (animation) name.
    pub animation: String,
    /// glTF node index.
    pub node: usize,
    /// Node name.
    pub node_name: String,
    /// `"translation"`, `"scale"`, or `"rotation"` (of a non-joint ancestor of the joints).
    pub property: &'static str,
    /// Largest distance of a key value from the rest value: in the parent's units for
    /// translation, unitless for scale, radians for rotation.
    pub max_deviation: f64,
}

impl std::fmt::Display for HeldChannel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let unit = match self.property {
            "rotation" => " rad",
            "translation" => " units",
            _ => "",
        };
        write!(
            f,
            "clip {}: the {} of node {} ({}) is animated, up to {:.3}{unit} from rest, and held \
             at rest: the pose vector carries joint rotations only",
            self.animation, self.property, self.node, self.node_name, self.max_deviation
        )
    }
}

/// A glTF skinned character and its animations; see the module docs for the conventions.
#[derive(Clone, Debug)]
pub struct GltfRig {
    path: PathBuf,
    fps: f64,
    bind: Mesh,
    skin: Skin,
    skeleton: Skeleton,
    joint_names: Vec<String>,
    angle_names: Vec<String>,
    animations: Vec<Animation>,
    held: Vec<HeldChannel>,
    uv_layout: Option<UvLayout>,
}

impl GltfRig {
    /// Loads `path` (`.gltf` with embedded or external buffers, or `.glb`); clips will be
    /// sampled at `fps` frames per second.
    pub fn load(path: &Path, fps: f64) -> Result<GltfRig, GltfError> {
        check_fps(fps, |fps| GltfError::Fps { fps })?;
        GltfRig::from_parts(load::read(path)?, path, fps)
    }

    /// Reads a document from `bytes` (a `.gltf`'s JSON or a `.glb`), as [`GltfRig::load`]
    /// reads the file `path`, which messages name. Buffers must be embedded (`data:` URIs or
    /// the GLB's BIN chunk): an external file is refused, as there is no directory to read it
    /// from.
    pub fn from_slice(bytes: &[u8], path: &Path, fps: f64) -> Result<GltfRig, GltfError> {
        check_fps(fps, |fps| GltfError::Fps { fps })?;
        GltfRig::from_parts(load::parse(bytes, path, None)?, path, fps)
    }

    fn from_parts(parts: load::Parts, path: &Path, fps: f64) -> Result<GltfRig, GltfError> {
        let joint_names: Vec<String> = parts
            .skeleton
            .joints
            .iter()
            .map(|&n| parts.node_names[n].clone())
            .collect();
        let angle_names = joint_names
            .iter()
            .flat_map(|j| ["x", "y", "z"].map(|axis| format!("{j}.{axis}")))
            .collect();
        let held = parts
            .animations
            .iter()
            .flat_map(|a| a.held_channels(&parts.skeleton, &parts.node_names))
            .collect();
        Ok(GltfRig {
            path: path.to_path_buf(),
            fps,
            bind: parts.bind,
            skin: parts.skin,
            skeleton: parts.skeleton,
            joint_names,
            angle_names,
            animations: parts.animations,
            held,
            uv_layout: parts.uv_layout,
        })
    }

    /// Names of the skin's joints, in skin (and pose-vector) order.
    pub fn joint_names(&self) -> &[String] {
        &self.joint_names
    }

    /// Animated properties held at rest when posing (translations, scales, non-joint
    /// rotations), with their largest deviation from rest.
    pub fn held_channels(&self) -> &[HeldChannel] {
        &self.held
    }

    /// Skinning matrices of frame `frame` of clip `name` with *every* animated property
    /// applied (translations, scales, non-joint nodes), as a glTF viewer would pose it: the
    /// reference the rotation-only pose vector is measured against.
    pub fn animated_joint_matrices(
        &self,
        name: &str,
        frame: usize,
    ) -> Result<Vec<Mat4>, GltfError> {
        let (animation, times) = self.frame_times(name)?;
        let &t = times.get(frame).ok_or_else(|| GltfError::Frames {
            path: self.path.clone(),
            clip: name.to_owned(),
            problem: format!("frame {frame} asked for, the clip has {}", times.len()),
        })?;
        Ok(self
            .skeleton
            .joint_matrices(&animation.locals_at(&self.skeleton.rest, t)))
    }

    /// Frames of the animation called `name` at the rig's frame rate, counted from its length
    /// (the times only, no pose is sampled).
    pub fn frame_count(&self, name: &str) -> Result<usize, GltfError> {
        Ok(self.frame_times(name)?.1.len())
    }

    /// The animation called `name` and its frame times `min(i/fps, end)`, `i = 0..=⌈end·fps⌉`.
    fn frame_times(&self, name: &str) -> Result<(&Animation, Vec<f64>), GltfError> {
        if self.animations.is_empty() {
            return Err(GltfError::NoAnimations {
                path: self.path.clone(),
            });
        }
        let animation = self
            .animations
            .iter()
            .find(|a| a.name == name)
            .ok_or_else(|| GltfError::UnknownClip {
                path: self.path.clone(),
                name: name.to_owned(),
                available: crate::text::shown_list(&self.clip_names()),
            })?;
        let end = animation.end();
        // The tolerance keeps an end that is a whole number of frames up to rounding (e.g.
        // 1.25 s at 24 fps) from gaining a near-duplicate last frame.
        // Refused before any frame is sampled: a frame rate or end time that asks for more
        // frames than one run bakes would otherwise allocate them first.
        let intervals = (end * self.fps - 1e-9).ceil().max(0.0);
        if intervals >= MAX_FRAMES as f64 {
            return Err(GltfError::Frames {
                path: self.path.clone(),
                clip: name.to_owned(),
                problem: format!(
                    "{end:.3} s at {} fps would have {:.0} frames, more than the {MAX_FRAMES} one \
                     run bakes or evaluates: take fewer frames or a lower frame rate",
                    self.fps,
                    intervals + 1.0
                ),
            });
        }
        let times = (0..=intervals as usize)
            .map(|i| (i as f64 / self.fps).min(end))
            .collect();
        Ok((animation, times))
    }

    /// The pose vector of a set of local transforms: each joint's rotation vector from rest.
    fn pose_of(&self, locals: &[Trs]) -> Vec<f64> {
        self.skeleton
            .joints
            .iter()
            .flat_map(|&node| {
                let delta = self.skeleton.rest[node].rotation.inverse() * locals[node].rotation;
                crate::rig::rotation_vector::log(delta).to_array()
            })
            .collect()
    }
}

/// The glTF character as a [`Rig`]. Its errors are [`RigError::Gltf`], naming the file.
impl Rig for GltfRig {
    /// glTF's world up (+Y) expressed in the rig's frame (the frame of the file's vertex
    /// data), unit length: e.g. +Z for a file that stores a Z-up mesh under a Y-up node.
    fn up(&self) -> Vec3 {
        self.skeleton
            .world_to_mesh
            .transform_vector3(DVec3::Y)
            .normalize()
            .as_vec3()
    }

    fn angle_names(&self) -> Vec<String> {
        self.angle_names.clone()
    }

    fn bind_mesh(&self) -> &Mesh {
        &self.bind
    }

    fn skin(&self) -> &Skin {
        &self.skin
    }

    /// Skinning matrices for a pose vector: every joint at its rest translation and scale,
    /// rotated by `exp` of its rotation vector from its rest rotation.
    fn joint_matrices(&self, pose: &[f64]) -> Result<Vec<Mat4>, RigError> {
        check_pose(pose, self.angle_names.len(), |i| {
            self.angle_names[i].clone()
        })
        .map_err(|source| GltfError::Pose {
            path: self.path.clone(),
            source,
        })?;
        let mut locals = self.skeleton.rest.clone();
        for (&node, r) in self.skeleton.joints.iter().zip(pose.chunks_exact(3)) {
            let delta = crate::rig::rotation_vector::exp(DVec3::new(r[0], r[1], r[2]));
            locals[node].rotation = self.skeleton.rest[node].rotation * delta;
        }
        Ok(self.skeleton.joint_matrices(&locals))
    }

    /// Names of the clips, in file order.
    fn clip_names(&self) -> Vec<String> {
        self.animations.iter().map(|a| a.name.clone()).collect()
    }

    /// The clip called `name`: one pose vector per frame.
    fn clip(&self, name: &str) -> Result<Clip, RigError> {
        let (animation, times) = self.frame_times(name)?;
        let mut frames: Vec<Vec<f64>> = times
            .iter()
            .map(|&t| self.pose_of(&animation.locals_at(&self.skeleton.rest, t)))
            .collect();
        crate::rig::rotation_vector::continue_turns(&mut frames, 0..self.skeleton.joints.len());
        Ok(Clip {
            name: name.to_owned(),
            fps: self.fps,
            frames,
        })
    }

    /// `TEXCOORD_0` of every skinned primitive; `None` if any primitive lacks it.
    fn uv_layout(&self) -> Option<&UvLayout> {
        self.uv_layout.as_ref()
    }
}

#[cfg(test)]
mod tests;
