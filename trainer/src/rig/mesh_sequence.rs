//! A skinless character made of meshes read from files (an OBJ sequence), each posed by its
//! row of joint angles: the light-map commands, written for rigs, take OBJ sequences through
//! it. It poses only its own rows (there is no skeleton to pose anything else), its first
//! mesh stands as the bind pose, and its one joint never moves, so models of it learn in
//! world space.

use std::collections::HashMap;

use glam::Mat4;

use super::mesh::Mesh;
use super::skin::Skin;
use super::uv::UvLayout;
use super::{Clip, PoseError, Rig, RigError, check_pose};

/// Why a mesh sequence cannot be built or posed. Every variant names the sequence.
#[derive(Debug, thiserror::Error)]
pub enum MeshSequenceError {
    /// Not one row of angles per mesh, or no mesh.
    #[error("{sequence}: {meshes} meshes and {rows} rows of angles: one row per mesh is needed")]
    Rows {
        /// The sequence.
        sequence: String,
        /// Meshes read.
        meshes: usize,
        /// Rows of angles.
        rows: usize,
    },
    /// Two rows with the same angles and different meshes: posing by angles is ambiguous.
    #[error(
        "{sequence}: rows {first} and {second} of the angles are the same pose but their meshes differ: each mesh is posed by its angles, so they must differ"
    )]
    SamePose {
        /// The sequence.
        sequence: String,
        /// 1-based data rows.
        first: usize,
        /// 1-based data rows.
        second: usize,
    },
    /// A pose vector of the right length that is none of the rows.
    #[error(
        "{sequence}: no mesh of the sequence has the angles {pose:?}: meshes read from files pose only their own rows"
    )]
    UnknownPose {
        /// The sequence.
        sequence: String,
        /// The pose asked for.
        pose: Vec<f64>,
    },
    /// A pose vector of the wrong length or with a NaN.
    #[error("{sequence}: {error}")]
    Pose {
        /// The sequence.
        sequence: String,
        /// What is wrong with it.
        error: PoseError,
    },
    /// A clip other than the sequence's one.
    #[error("{sequence}: no clip {}: an OBJ sequence is one clip, its files in order", crate::text::quote(.name))]
    UnknownClip {
        /// The sequence.
        sequence: String,
        /// The name asked for.
        name: String,
    },
}

/// Meshes read from files with one row of joint angles each (see the module docs).
pub struct MeshSequence {
    name: String,
    meshes: Vec<Mesh>,
    angles: Vec<Vec<f64>>,
    uvs: Option<UvLayout>,
    /// Every vertex on joint 0, whose matrix is the identity in every pose.
    skin: Skin,
    /// The row of each pose's bits.
    rows: HashMap<Vec<u64>, usize>,
}

impl MeshSequence {
    /// The sequence `name` (its directory, in messages and as its clip's name): `meshes`
    /// sharing one topology, one row of `angles` each, and the first mesh's texture UVs.
    pub fn new(
        name: String,
        meshes: Vec<Mesh>,
        angles: Vec<Vec<f64>>,
        uvs: Option<UvLayout>,
    ) -> Result<MeshSequence, MeshSequenceError> {
        if meshes.is_empty() || meshes.len() != angles.len() {
            return Err(MeshSequenceError::Rows {
                sequence: name,
                meshes: meshes.len(),
                rows: angles.len(),
            });
        }
        let mut rows: HashMap<Vec<u64>, usize> = HashMap::new();
        for (i, row) in angles.iter().enumerate() {
            if let Some(&first) = rows.get(&bits(row))
                && meshes[first].positions != meshes[i].positions
            {
                return Err(MeshSequenceError::SamePose {
                    sequence: name,
                    first: first + 1,
                    second: i + 1,
                });
            }
            rows.entry(bits(row)).or_insert(i);
        }
        let one_joint = std::iter::repeat_n([(0u32, 1.0f32)], meshes[0].vertex_count());
        let skin = Skin::from_influences(one_joint).expect("weight 1 on one joint is a skin");
        Ok(MeshSequence {
            name,
            meshes,
            angles,
            uvs,
            skin,
            rows,
        })
    }

    /// The row `pose` is, after checking it is a pose vector of this sequence.
    fn row(&self, pose: &[f64]) -> Result<usize, MeshSequenceError> {
        let sequence = || self.name.clone();
        check_pose(pose, self.angles[0].len(), |i| {
            self.angle_names()[i].clone()
        })
        .map_err(|error| MeshSequenceError::Pose {
            sequence: sequence(),
            error,
        })?;
        self.rows
            .get(&bits(pose))
            .copied()
            .ok_or_else(|| MeshSequenceError::UnknownPose {
                sequence: sequence(),
                pose: pose.to_vec(),
            })
    }
}

/// A row's exact bits: rows are looked up as read, never computed.
fn bits(row: &[f64]) -> Vec<u64> {
    row.iter().map(|a| a.to_bits()).collect()
}

impl Rig for MeshSequence {
    /// `column 1`, `column 2`, …: the angles file's columns.
    fn angle_names(&self) -> Vec<String> {
        (1..=self.angles[0].len())
            .map(|c| format!("column {c}"))
            .collect()
    }

    fn bind_mesh(&self) -> &Mesh {
        &self.meshes[0]
    }

    fn rest_pose(&self) -> Vec<f64> {
        self.angles[0].clone()
    }

    fn skin(&self) -> &Skin {
        &self.skin
    }

    fn joint_matrices(&self, pose: &[f64]) -> Result<Vec<Mat4>, RigError> {
        self.row(pose)?;
        Ok(vec![Mat4::IDENTITY])
    }

    fn pose(&self, pose: &[f64]) -> Result<Mesh, RigError> {
        Ok(self.meshes[self.row(pose)?].clone())
    }

    fn clip_names(&self) -> Vec<String> {
        vec![self.name.clone()]
    }

    fn clip(&self, name: &str) -> Result<Clip, RigError> {
        if name != self.name {
            return Err(MeshSequenceError::UnknownClip {
                sequence: self.name.clone(),
                name: name.to_owned(),
            }
            .into());
        }
        Ok(Clip {
            name: self.name.clone(),
            // Files have no rate: one frame a file.
            fps: 1.0,
            frames: self.angles.clone(),
        })
    }

    fn uv_layout(&self) -> Option<&UvLayout> {
        self.uvs.as_ref()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mesh(z: f32) -> Mesh {
        let positions = vec![[0.0, 0.0, z], [1.0, 0.0, z], [0.0, 1.0, z]];
        Mesh::with_area_weighted_normals(positions, vec![[0, 1, 2]])
    }

    /// Each row poses its own mesh, the first is the bind and rest pose, the one clip is the
    /// rows in order; any other pose, a row of the wrong length, or two rows of one pose with
    /// different meshes are refused naming the sequence.
    #[test]
    fn poses_its_own_rows_only() {
        let angles = vec![vec![0.0, 0.1], vec![0.5, 0.2]];
        let seq = MeshSequence::new("seq".into(), vec![mesh(0.0), mesh(1.0)], angles, None);
        let seq = seq.unwrap();
        assert_eq!(seq.pose(&[0.5, 0.2]).unwrap(), mesh(1.0));
        assert_eq!(seq.bind_mesh(), &mesh(0.0));
        assert_eq!(seq.rest_pose(), vec![0.0, 0.1]);
        assert_eq!(seq.clip("seq").unwrap().frames.len(), 2);
        assert_eq!(
            seq.joint_matrices(&[0.0, 0.1]).unwrap(),
            vec![Mat4::IDENTITY]
        );
        assert_eq!(seq.skin().joint_count(), 1);
        let unknown = seq.pose(&[0.5, 0.3]).unwrap_err().to_string();
        assert!(
            unknown.contains("seq: no mesh") && unknown.contains("0.3"),
            "{unknown}"
        );
        let short = seq.pose(&[0.5]).unwrap_err().to_string();
        assert!(short.contains("seq: a pose needs 2 values"), "{short}");
        let same = vec![vec![0.0], vec![0.0]];
        let twice = MeshSequence::new("seq".into(), vec![mesh(0.0), mesh(1.0)], same, None);
        let error = twice.err().unwrap().to_string();
        assert!(error.contains("rows 1 and 2"), "{error}");
    }
}
