//! Reading a glTF document into the rig's parts: the merged bind mesh and skin of the skinned
//! mesh nodes, the node hierarchy, and the animations as curves. Every check that can fail on
//! a malformed file happens here, once, so posing and sampling cannot fail later.

use std::collections::HashMap;
use std::path::Path;

use glam::{DMat4, DQuat, DVec3};
use gltf::animation::util::ReadOutputs;
use gltf::mesh::{Mode, Semantic};

use super::animation::{Animation, Track};
use super::curve::{Curve, Interpolation};
use super::skeleton::{Skeleton, Trs};
use super::spec;
use super::{GltfError, item};
use crate::input::{InputKind, read_input};
use crate::rig::mesh::{Mesh, area_weighted_normals};
use crate::rig::skin::Skin;
use crate::rig::uv::UvLayout;

/// Everything [`super::GltfRig`] is built from.
pub struct Parts {
    pub bind: Mesh,
    pub skin: Skin,
    pub skeleton: Skeleton,
    /// A unique display name per node (`name`, `node<i>` when unnamed, `name#<i>` when the
    /// name is shared).
    pub node_names: Vec<String>,
    pub animations: Vec<Animation>,
    /// `TEXCOORD_0` per triangle corner, if every skinned primitive has it.
    pub uv_layout: Option<UvLayout>,
}

/// Each vertex's `(joint, weight)` influences, as [`Skin::from_influences`] takes them.
type Influences = Vec<Vec<(u32, f32)>>;

/// The merged bind mesh, its influences and its `TEXCOORD_0` (see [`merge_primitives`]).
type Merged = (Mesh, Influences, Option<Vec<[f32; 2]>>);

/// Reads `path` (`.gltf` with embedded or external buffers, or `.glb`).
pub fn read(path: &Path) -> Result<Parts, GltfError> {
    let bytes = read_input(path, InputKind::Gltf)?;
    parse(&bytes, path, path.parent())
}

/// Reads the document in `bytes` (the contents of `path`, which messages name); external
/// buffers are read relative to `base`, and refused without one.
pub fn parse(bytes: &[u8], path: &Path, base: Option<&Path>) -> Result<Parts, GltfError> {
    let loaded = super::document::parse(bytes, path, base)?;
    let (doc, buffers) = (&loaded.document, &loaded.buffers[..]);
    let invalid = invalid_in(path);

    let (skinned, skin) = skinned_nodes(doc, path)?;
    // Before any reader of the gltf crate touches an accessor.
    spec::check(doc, buffers, &skinned, &skin).map_err(|(item, problem)| invalid(item, problem))?;
    let node_names = node_names(doc);
    let parents = parents(doc).map_err(|(node, problem)| {
        invalid(
            item("node", node, doc.nodes().nth(node).and_then(|n| n.name())),
            problem,
        )
    })?;
    let rest = rest_transforms(doc, path)?;
    let skin_item = item("skin", skin.index(), skin.name());
    let joints: Vec<usize> = skin.joints().map(|n| n.index()).collect();
    if joints.is_empty() {
        return Err(invalid(skin_item, "has no joints".into()));
    }
    check_scales(&rest, &parents, &joints, skinned[0].index(), &node_names)
        .map_err(|(node, problem)| invalid(node, problem))?;
    let joint_names: Vec<&str> = joints.iter().map(|&j| node_names[j].as_str()).collect();
    let inverse_bind = inverse_binds(&skin, buffers, &joint_names, path)?;
    let (bind, influences, uvs) = merge_primitives(&skinned, buffers, joints.len(), path)?;
    let uv_layout = uvs.map(|uvs| UvLayout::from_vertex_uvs(&uvs, &bind.triangles));
    if bind.triangles.is_empty() {
        return Err(invalid(
            "skinned meshes".into(),
            "no triangles: there is no surface to bake".into(),
        ));
    }
    let skin = Skin::from_influences(&influences).map_err(|source| GltfError::Skin {
        path: path.to_path_buf(),
        source,
    })?;
    let skeleton = Skeleton::new(parents, rest, joints, inverse_bind, skinned[0].index());
    Ok(Parts {
        bind,
        skin,
        skeleton,
        animations: animations(doc, buffers, &node_names, path)?,
        node_names,
        uv_layout,
    })
}

/// The error for `item` of the file at `path`.
fn invalid_in(path: &Path) -> impl Fn(String, String) -> GltfError + '_ {
    move |item, problem| GltfError::Invalid {
        path: path.to_path_buf(),
        item,
        problem,
    }
}

/// The nodes with both a mesh and a skin, in node order, and the skin they all share.
fn skinned_nodes<'d>(
    doc: &'d gltf::Document,
    path: &Path,
) -> Result<(Vec<gltf::Node<'d>>, gltf::Skin<'d>), GltfError> {
    let skinned: Vec<gltf::Node> = doc
        .nodes()
        .filter(|n| n.mesh().is_some() && n.skin().is_some())
        .collect();
    let Some(first) = skinned.first() else {
        return Err(GltfError::NoSkin {
            path: path.to_path_buf(),
        });
    };
    let skin = first
        .skin()
        .unwrap_or_else(|| unreachable!("filtered on skin"));
    if skinned
        .iter()
        .any(|n| n.skin().map(|s| s.index()) != Some(skin.index()))
    {
        let nodes = skinned
            .iter()
            .map(|n| {
                let s = n.skin().map_or(0, |s| s.index());
                format!("{} uses skin {s}", item("node", n.index(), n.name()))
            })
            .collect::<Vec<_>>()
            .join(", ");
        return Err(GltfError::SkinsDiffer {
            path: path.to_path_buf(),
            nodes,
        });
    }
    Ok((skinned, skin))
}

/// Every node's rest transform, which must be finite with a nonzero rotation; a `matrix` must
/// be a translation, rotation and scale, as glTF requires (a shear or projection has no TRS
/// to animate from).
fn rest_transforms(doc: &gltf::Document, path: &Path) -> Result<Vec<Trs>, GltfError> {
    let invalid = invalid_in(path);
    doc.nodes()
        .map(|n| {
            let (t, r, s) = n.transform().decomposed();
            let rotation = DQuat::from_array(r.map(f64::from));
            let trs = Trs {
                translation: DVec3::from_array(t.map(f64::from)),
                rotation: rotation.normalize(),
                scale: DVec3::from_array(s.map(f64::from)),
            };
            let node = || item("node", n.index(), n.name());
            let finite =
                trs.translation.is_finite() && trs.rotation.is_finite() && trs.scale.is_finite();
            if !finite {
                return Err(invalid(
                    node(),
                    "its transform is not finite, its rotation is zero or its matrix is singular"
                        .into(),
                ));
            }
            if let gltf::scene::Transform::Matrix { matrix } = n.transform() {
                let m = DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from)));
                let size = m
                    .to_cols_array()
                    .iter()
                    .fold(1.0, |a: f64, v| a.max(v.abs()));
                if !m.abs_diff_eq(trs.matrix(), 1e-4 * size) {
                    return Err(invalid(
                        node(),
                        "its matrix is not a translation, rotation and scale (it shears or \
                         projects), which glTF requires of a node's matrix"
                            .into(),
                    ));
                }
            }
            Ok(trs)
        })
        .collect()
}

/// Errors `(node, problem)` when a joint, the skinned mesh node or an ancestor of one has a
/// zero scale: it collapses the mesh below it, and the bind pose has no inverse.
fn check_scales(
    rest: &[Trs],
    parents: &[Option<usize>],
    joints: &[usize],
    mesh_node: usize,
    node_names: &[String],
) -> Result<(), (String, String)> {
    let mut seen = vec![false; rest.len()];
    for &start in joints.iter().chain([&mesh_node]) {
        let mut node = Some(start);
        while let Some(n) = node.filter(|&n| !seen[n]) {
            seen[n] = true;
            let scale = rest[n].scale;
            if scale.abs().min_element() < f64::from(f32::MIN_POSITIVE) {
                return Err((
                    format!("node {n} {}", crate::text::quote(&node_names[n])),
                    format!(
                        "has scale {:?}: a zero scale collapses the skinned mesh",
                        scale.to_array()
                    ),
                ));
            }
            node = parents[n];
        }
    }
    Ok(())
}

/// The skin's inverse bind matrices, one per joint (`joint_names` in skin order): finite,
/// invertible, with the fourth row `[0, 0, 0, 1]` glTF requires. (The accessor's type and
/// count were checked by [`spec::check`].)
fn inverse_binds(
    skin: &gltf::Skin,
    buffers: &[gltf::buffer::Data],
    joint_names: &[&str],
    path: &Path,
) -> Result<Vec<DMat4>, GltfError> {
    let invalid = invalid_in(path);
    let get = |b: gltf::Buffer| buffers.get(b.index()).map(|d| d.0.as_slice());
    let Some(accessor) = skin.inverse_bind_matrices() else {
        // glTF: without the accessor every inverse bind matrix is the identity.
        return Ok(vec![DMat4::IDENTITY; joint_names.len()]);
    };
    let matrices: Vec<DMat4> = skin
        .reader(get)
        .read_inverse_bind_matrices()
        .ok_or_else(|| unreadable(&invalid, &accessor))?
        .take(joint_names.len())
        .map(|m| DMat4::from_cols_array_2d(&m.map(|c| c.map(f64::from))))
        .collect();
    for (k, (m, joint)) in matrices.iter().zip(joint_names).enumerate() {
        let problem = if !m.is_finite() {
            "holds a value that is not finite"
        } else if singular(m) {
            "is singular (its 3×3 part has no inverse): it would collapse the joint's vertices"
        } else if !m.row(3).abs_diff_eq(glam::DVec4::W, 1e-3) {
            "does not have the fourth row [0, 0, 0, 1] glTF requires"
        } else {
            continue;
        };
        return Err(invalid(
            format!(
                "{} accessor {} matrix {k} (joint {})",
                item("skin", skin.index(), skin.name()),
                accessor.index(),
                crate::text::quote(joint)
            ),
            format!("{problem}: {:?}", m.to_cols_array()),
        ));
    }
    Ok(matrices)
}

/// Whether the linear part of `m` (finite) has, relative to its columns' lengths, no inverse.
fn singular(m: &DMat4) -> bool {
    let a = glam::DMat3::from_mat4(*m);
    let lengths = a.x_axis.length() * a.y_axis.length() * a.z_axis.length();
    // Hadamard: |det| ≤ the product of the column lengths, with equality for orthogonal ones.
    a.determinant().abs() <= 1e-9 * lengths
}

/// Every primitive of the skinned nodes merged in order into the bind mesh (vertices in
/// accessor order), with each vertex's joint influences and its `TEXCOORD_0` (`None` unless
/// every primitive has one: a layout with holes lays nothing out).
fn merge_primitives(
    skinned: &[gltf::Node],
    buffers: &[gltf::buffer::Data],
    joint_count: usize,
    path: &Path,
) -> Result<Merged, GltfError> {
    let invalid = invalid_in(path);
    let get = |b: gltf::Buffer| buffers.get(b.index()).map(|d| d.0.as_slice());
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut triangles = Vec::new();
    let mut influences: Influences = Vec::new();
    let mut uvs = Some(Vec::new());
    for node in skinned {
        let mesh = node
            .mesh()
            .unwrap_or_else(|| unreachable!("filtered on mesh"));
        for primitive in mesh.primitives() {
            let part = read_primitive(&primitive, get, joint_count).map_err(|problem| {
                invalid(
                    format!(
                        "{} primitive {}",
                        item("mesh", mesh.index(), mesh.name()),
                        primitive.index()
                    ),
                    problem,
                )
            })?;
            let base = positions.len() as u32;
            triangles.extend(part.triangles.iter().map(|t| t.map(|i| i + base)));
            normals.extend(
                part.normals
                    .unwrap_or_else(|| area_weighted_normals(&part.positions, &part.triangles)),
            );
            positions.extend(part.positions);
            influences.extend(part.influences);
            uvs = uvs.zip(part.uvs).map(|(mut all, part)| {
                all.extend(part);
                all
            });
        }
    }
    Ok((
        Mesh {
            positions,
            normals,
            triangles,
        },
        influences,
        uvs,
    ))
}

/// The animations as curves per node; a repeated name gets `#<index>` appended.
fn animations(
    doc: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    node_names: &[String],
    path: &Path,
) -> Result<Vec<Animation>, GltfError> {
    let invalid = invalid_in(path);
    let get = |b: gltf::Buffer| buffers.get(b.index()).map(|d| d.0.as_slice());
    let mut animations: Vec<Animation> = Vec::new();
    for animation in doc.animations() {
        let mut name = animation
            .name()
            .map_or_else(|| format!("animation{}", animation.index()), str::to_owned);
        if animations.iter().any(|a| a.name == name) {
            name = format!("{name}#{}", animation.index());
        }
        let mut tracks = Vec::new();
        for channel in animation.channels() {
            let node = channel.target().node();
            let channel_item = format!(
                "{} channel {} (node {})",
                item("animation", animation.index(), animation.name()),
                channel.index(),
                crate::text::quote(&node_names[node.index()])
            );
            if let Some(track) = read_track(&channel, get)
                .map_err(|problem| invalid(channel_item.clone(), problem))?
            {
                tracks.push((node.index(), track));
            }
        }
        animations.push(Animation { name, tracks });
    }
    Ok(animations)
}

/// The error for an accessor whose bytes lie outside its buffer view or buffer.
fn unreadable(
    invalid: &impl Fn(String, String) -> GltfError,
    accessor: &gltf::Accessor,
) -> GltfError {
    invalid(
        format!("accessor {}", accessor.index()),
        "its data lies outside its buffer view or buffer".into(),
    )
}

fn node_names(doc: &gltf::Document) -> Vec<String> {
    let base: Vec<String> = doc
        .nodes()
        .map(|n| {
            n.name()
                .map_or_else(|| format!("node{}", n.index()), str::to_owned)
        })
        .collect();
    let mut uses: HashMap<&str, usize> = HashMap::new();
    for name in &base {
        *uses.entry(name).or_default() += 1;
    }
    base.iter()
        .enumerate()
        .map(|(i, name)| {
            if uses[name.as_str()] > 1 {
                format!("{name}#{i}")
            } else {
                name.clone()
            }
        })
        .collect()
}

/// Each node's parent; a node listed as the child of two nodes, or a cycle, is an error
/// `(node, problem)`. Linear in the number of nodes.
fn parents(doc: &gltf::Document) -> Result<Vec<Option<usize>>, (usize, String)> {
    let count = doc.nodes().len();
    let mut parents = vec![None; count];
    for node in doc.nodes() {
        for child in node.children() {
            if let Some(other) = parents[child.index()].replace(node.index()) {
                return Err((
                    child.index(),
                    format!("is a child of both node {other} and node {}", node.index()),
                ));
            }
        }
    }
    // Walk up from each node, marking the walk with its start; meeting the mark again is a
    // cycle, meeting a node an earlier walk finished is not.
    const DONE: usize = usize::MAX;
    let mut mark = vec![0; count];
    for start in 0..count {
        let mut node = Some(start);
        while let Some(n) = node.filter(|&n| mark[n] != DONE) {
            if mark[n] == start + 1 {
                return Err((n, "is its own ancestor (the node graph has a cycle)".into()));
            }
            mark[n] = start + 1;
            node = parents[n];
        }
        let mut node = Some(start);
        while let Some(n) = node.filter(|&n| mark[n] == start + 1) {
            mark[n] = DONE;
            node = parents[n];
        }
    }
    Ok(parents)
}

/// One primitive's vertices, in accessor order.
struct Part {
    positions: Vec<[f32; 3]>,
    normals: Option<Vec<[f32; 3]>>,
    triangles: Vec<[u32; 3]>,
    influences: Influences,
    uvs: Option<Vec<[f32; 2]>>,
}

fn read_primitive<'a, 's, F>(
    primitive: &'a gltf::Primitive<'a>,
    get: F,
    joint_count: usize,
) -> Result<Part, String>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let reader = primitive.reader(get);
    let positions: Vec<[f32; 3]> = match primitive.get(&Semantic::Positions) {
        None => return Err("has no POSITION attribute".into()),
        Some(_) => reader
            .read_positions()
            .ok_or_else(|| unreadable_attribute(primitive, Semantic::Positions))?
            .collect(),
    };
    let n = positions.len();
    if let Some(v) = positions
        .iter()
        .position(|p| !p.iter().all(|c| c.is_finite()))
    {
        return Err(format!("POSITION {v} is not finite"));
    }
    let normals = read_normals(primitive, &reader, n)?;
    let indices: Vec<u32> = match primitive.indices() {
        None => (0..n as u32).collect(),
        Some(_) => reader
            .read_indices()
            .ok_or_else(|| "its indices accessor lies outside its buffer".to_owned())?
            .into_u32()
            .collect(),
    };
    if let Some(&i) = indices.iter().find(|&&i| i as usize >= n) {
        return Err(format!("index {i} is out of range for {n} vertices"));
    }
    let triangles = triangulate(primitive.mode(), &indices)?;
    let influences = read_influences(primitive, &reader, n, joint_count)?;
    let uvs = read_uvs(primitive, &reader, n)?;
    Ok(Part {
        positions,
        normals,
        triangles,
        influences,
        uvs,
    })
}

/// The message for an attribute whose accessor lies outside its buffer view or buffer.
fn unreadable_attribute(primitive: &gltf::Primitive, semantic: Semantic) -> String {
    let index = primitive.get(&semantic).map_or(0, |a| a.index());
    format!("accessor {index} ({semantic:?}): its data lies outside its buffer view or buffer")
}

/// Errors unless an attribute has one element per position (`n`).
fn check_count(semantic: Semantic, got: usize, n: usize) -> Result<(), String> {
    if got == n {
        Ok(())
    } else {
        Err(format!(
            "{semantic:?} has {got} elements but POSITION has {n}"
        ))
    }
}

/// The primitive's `NORMAL`s renormalised, if it has them (`n` positions).
fn read_normals<'a, 's, F>(
    primitive: &'a gltf::Primitive<'a>,
    reader: &gltf::mesh::Reader<'a, 's, F>,
    n: usize,
) -> Result<Option<Vec<[f32; 3]>>, String>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    if primitive.get(&Semantic::Normals).is_none() {
        return Ok(None);
    }
    let raw: Vec<[f32; 3]> = reader
        .read_normals()
        .ok_or_else(|| unreadable_attribute(primitive, Semantic::Normals))?
        .collect();
    check_count(Semantic::Normals, raw.len(), n)?;
    let unit = raw
        .iter()
        .enumerate()
        .map(|(v, &normal)| {
            glam::Vec3::from(normal)
                .try_normalize()
                .map(|n| n.to_array())
                .ok_or_else(|| format!("NORMAL {v} ({normal:?}) has no direction"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Some(unit))
}

/// The primitive's `TEXCOORD_0` as floats (normalized integers mapped to `[0,1]`), if it has
/// them (`n` positions). Non-finite values are kept: [`crate::rig::uv::Atlas::build`]
/// refuses them naming the triangle, while the rig stays usable without a light map.
fn read_uvs<'a, 's, F>(
    primitive: &'a gltf::Primitive<'a>,
    reader: &gltf::mesh::Reader<'a, 's, F>,
    n: usize,
) -> Result<Option<Vec<[f32; 2]>>, String>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    if primitive.get(&Semantic::TexCoords(0)).is_none() {
        return Ok(None);
    }
    let uvs: Vec<[f32; 2]> = reader
        .read_tex_coords(0)
        .ok_or_else(|| unreadable_attribute(primitive, Semantic::TexCoords(0)))?
        .into_f32()
        .collect();
    check_count(Semantic::TexCoords(0), uvs.len(), n)?;
    Ok(Some(uvs))
}

/// Every vertex's `(joint, weight)` influences over all `JOINTS_n`/`WEIGHTS_n` sets (`n`
/// vertices, joints below `joint_count` wherever the weight is nonzero).
fn read_influences<'a, 's, F>(
    primitive: &'a gltf::Primitive<'a>,
    reader: &gltf::mesh::Reader<'a, 's, F>,
    n: usize,
    joint_count: usize,
) -> Result<Influences, String>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let mut influences = vec![Vec::new(); n];
    for set in 0.. {
        if primitive.get(&Semantic::Joints(set)).is_none() {
            if set == 0 {
                return Err(
                    "has no JOINTS_0 attribute: a skinned mesh needs joint influences".into(),
                );
            }
            break;
        }
        let joints: Vec<[u16; 4]> = reader
            .read_joints(set)
            .ok_or_else(|| unreadable_attribute(primitive, Semantic::Joints(set)))?
            .into_u16()
            .collect();
        if primitive.get(&Semantic::Weights(set)).is_none() {
            return Err(format!("has JOINTS_{set} but no WEIGHTS_{set}"));
        }
        let weights: Vec<[f32; 4]> = reader
            .read_weights(set)
            .ok_or_else(|| unreadable_attribute(primitive, Semantic::Weights(set)))?
            .into_f32()
            .collect();
        check_count(Semantic::Joints(set), joints.len(), n)?;
        check_count(Semantic::Weights(set), weights.len(), n)?;
        for (v, (j, w)) in joints.iter().zip(&weights).enumerate() {
            for (&joint, &weight) in j.iter().zip(w) {
                if weight != 0.0 && usize::from(joint) >= joint_count {
                    return Err(format!(
                        "JOINTS_{set} of vertex {v} names joint {joint}, but the skin has {joint_count}"
                    ));
                }
                influences[v].push((u32::from(joint), weight));
            }
        }
    }
    Ok(influences)
}

/// Triangles of a primitive from its index list. Strips and fans are unrolled (strip
/// triangles alternate winding so all face the same way); points and lines have no surface to
/// shadow or be shadowed, so they are an error rather than silently dropped geometry.
fn triangulate(mode: Mode, indices: &[u32]) -> Result<Vec<[u32; 3]>, String> {
    let n = indices.len();
    Ok(match mode {
        Mode::Triangles => {
            if !n.is_multiple_of(3) {
                return Err(format!("TRIANGLES with {n} indices, not a multiple of 3"));
            }
            indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect()
        }
        Mode::TriangleStrip => (0..n.saturating_sub(2))
            .map(|i| {
                let [a, b, c] = [indices[i], indices[i + 1], indices[i + 2]];
                if i % 2 == 0 { [a, b, c] } else { [b, a, c] }
            })
            .collect(),
        Mode::TriangleFan => (1..n.saturating_sub(1))
            .map(|i| [indices[0], indices[i], indices[i + 1]])
            .collect(),
        other => {
            return Err(format!(
                "mode {other:?} is not supported: only TRIANGLES, TRIANGLE_STRIP and \
                 TRIANGLE_FAN have a surface to bake"
            ));
        }
    })
}

/// The curve of one channel; `None` for morph-target weights, which the rig does not apply.
fn read_track<'a, 's, F>(
    channel: &gltf::animation::Channel<'a>,
    get: F,
) -> Result<Option<Track>, String>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    let sampler = channel.sampler();
    let interpolation = match sampler.interpolation() {
        gltf::animation::Interpolation::Step => Interpolation::Step,
        gltf::animation::Interpolation::Linear => Interpolation::Linear,
        gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
    };
    let reader = channel.reader(get);
    let accessors = format!(
        "sampler {} (input accessor {}, output accessor {})",
        sampler.index(),
        sampler.input().index(),
        sampler.output().index()
    );
    let times: Vec<f64> = reader
        .read_inputs()
        .ok_or_else(|| format!("{accessors}: input data lies outside its buffer"))?
        .map(f64::from)
        .collect();
    let outputs = reader
        .read_outputs()
        .ok_or_else(|| format!("{accessors}: output data lies outside its buffer"))?;
    let vectors = |it: gltf::accessor::Iter<'s, [f32; 3]>| -> Result<Vec<DVec3>, String> {
        it.map(|v| DVec3::from_array(v.map(f64::from)))
            .enumerate()
            .map(|(i, v)| {
                v.is_finite()
                    .then_some(v)
                    .ok_or_else(|| format!("{accessors}: output {i} is not finite"))
            })
            .collect()
    };
    let track = match outputs {
        ReadOutputs::Translations(it) => Track::Translation(
            Curve::new(times, vectors(it)?, interpolation)
                .map_err(|e| format!("{accessors}: {e}"))?,
        ),
        ReadOutputs::Scales(it) => Track::Scale(
            Curve::new(times, vectors(it)?, interpolation)
                .map_err(|e| format!("{accessors}: {e}"))?,
        ),
        ReadOutputs::Rotations(it) => {
            let cubic = interpolation == Interpolation::CubicSpline;
            let rotations = it
                .into_f32()
                .map(|q| DQuat::from_array(q.map(f64::from)))
                .enumerate()
                .map(|(i, q)| {
                    // Key values are unit rotations; CUBICSPLINE tangents are free 4-vectors.
                    let q = if cubic && i % 3 != 1 {
                        q
                    } else {
                        q.normalize()
                    };
                    q.is_finite().then_some(q).ok_or_else(|| {
                        format!("{accessors}: output {i} is not finite or is a zero rotation")
                    })
                })
                .collect::<Result<Vec<_>, _>>()?;
            Track::Rotation(
                Curve::new(times, rotations, interpolation)
                    .map_err(|e| format!("{accessors}: {e}"))?,
            )
        }
        ReadOutputs::MorphTargetWeights(_) => return Ok(None),
    };
    Ok(Some(track))
}
