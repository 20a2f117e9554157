//! Every accessor the rig reads, checked against what glTF 2.0 allows for its use before any
//! reader of the `gltf` crate touches it. The crate's readers trust the file: a component
//! type they do not expect reaches `unreachable!()`, a type of the wrong width is read as
//! another (a VEC2 `POSITION` as VEC3), a count of 0 or a huge one underflows or overflows the
//! byte range they slice, a stride shorter than the element fails an assertion, an animation
//! channel's target is never validated, and out-of-range or unordered sparse indices are
//! silently skipped. Checked here, once, with the accessor, its use and what the
//! specification allows named:
//!
//! - type, component type and `normalized` per use (glTF 2.0 §3.7.2.1 for mesh attributes,
//!   §3.7.2.1 indices, §3.7.3 inverse bind matrices, §3.11 animation samplers);
//! - the bytes: `count ≥ 1`, the buffer view inside its buffer, the stride at least the
//!   element, every element inside the view, sparse indices strictly increasing below `count`;
//! - counts: each attribute one element per `POSITION`, at least one inverse bind matrix per
//!   joint, and totals bounded ([`MAX_VERTICES`], [`MAX_INDICES`], [`MAX_KEYS`]) so that no
//!   file, however small, makes the reader allocate without bound (an accessor without a
//!   buffer view is `count` zeros, and many primitives or channels may share one accessor).

use gltf::accessor::{DataType, Dimensions};
use gltf::animation::Property;
use gltf::json::validation::Checked;
use gltf::mesh::Semantic;

use super::item;

/// Most vertices the merged skinned meshes may have: what a model blob can hold.
pub const MAX_VERTICES: usize = aprt_core::MAX_VERTICES;
/// Most indices the merged skinned meshes may have (or vertices, for non-indexed primitives):
/// 128 MiB of `u32`, eight indices (two to three triangles) per vertex at the vertex limit;
/// closed meshes have about six.
pub const MAX_INDICES: usize = 8 * MAX_VERTICES;
/// Most key times plus key values over all animation channels (256 MiB as f64 quaternions).
pub const MAX_KEYS: usize = 1 << 23;

/// A component type and whether the use requires `normalized` to be true.
type Component = (DataType, bool);

const FLOAT: &[Component] = &[(DataType::F32, false)];
const UNSIGNED: &[Component] = &[
    (DataType::U8, false),
    (DataType::U16, false),
    (DataType::U32, false),
];
const JOINT_INDICES: &[Component] = &[(DataType::U8, false), (DataType::U16, false)];
const WEIGHTS: &[Component] = &[
    (DataType::F32, false),
    (DataType::U8, true),
    (DataType::U16, true),
];
const TEX_COORDS: &[Component] = &[
    (DataType::F32, false),
    (DataType::U8, true),
    (DataType::U16, true),
];
const FLOAT_OR_NORMALIZED: &[Component] = &[
    (DataType::F32, false),
    (DataType::I8, true),
    (DataType::U8, true),
    (DataType::I16, true),
    (DataType::U16, true),
];

/// What an accessor is read as: its use, the types and component types glTF 2.0 allows.
struct Use {
    what: String,
    dimensions: Dimensions,
    components: &'static [Component],
}

/// Checks every accessor the rig will read: the skinned nodes' primitives, the skin's inverse
/// bind matrices, and every animation channel (target and sampler accessors). Errors are
/// `(item, problem)`.
pub fn check(
    doc: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    skinned: &[gltf::Node],
    skin: &gltf::Skin,
) -> Result<(), (String, String)> {
    let mut vertices = 0usize;
    let mut indices = 0usize;
    for node in skinned {
        let Some(mesh) = node.mesh() else { continue };
        let mesh_item = item("mesh", mesh.index(), mesh.name());
        if mesh.primitives().len() == 0 {
            return Err((
                mesh_item,
                "has no primitives: there is no surface to bake".into(),
            ));
        }
        for primitive in mesh.primitives() {
            let within = format!("{mesh_item} primitive {}", primitive.index());
            let n = check_primitive(&primitive, &within, buffers)?;
            vertices = vertices.saturating_add(n);
            indices = indices.saturating_add(primitive.indices().map_or(n, |a| a.count()));
        }
    }
    if vertices > MAX_VERTICES {
        return Err((
            "skinned meshes".into(),
            format!("{vertices} vertices in all, more than the {MAX_VERTICES} a model holds"),
        ));
    }
    if indices > MAX_INDICES {
        return Err((
            "skinned meshes".into(),
            format!("{indices} indices in all, more than the {MAX_INDICES} the reader takes"),
        ));
    }
    if let Some(accessor) = skin.inverse_bind_matrices() {
        let what = format!(
            "{} inverseBindMatrices",
            item("skin", skin.index(), skin.name())
        );
        let joints = skin.joints().len();
        check_accessor(
            &accessor,
            &uses(what.clone(), Dimensions::Mat4, FLOAT),
            buffers,
        )?;
        if accessor.count() < joints {
            return Err((
                format!("accessor {} ({what})", accessor.index()),
                format!(
                    "holds {} matrices for {joints} joints: glTF needs one per joint",
                    accessor.count()
                ),
            ));
        }
    }
    check_animations(doc, buffers)
}

fn uses(what: String, dimensions: Dimensions, components: &'static [Component]) -> Use {
    Use {
        what,
        dimensions,
        components,
    }
}

/// One primitive's attributes and indices; returns its vertex count.
fn check_primitive(
    primitive: &gltf::Primitive,
    within: &str,
    buffers: &[gltf::buffer::Data],
) -> Result<usize, (String, String)> {
    let Some(position) = primitive.get(&Semantic::Positions) else {
        return Err((within.to_owned(), "has no POSITION attribute".into()));
    };
    let n = position.count();
    for (semantic, accessor) in primitive.attributes() {
        let (dimensions, components) = match semantic {
            Semantic::Positions | Semantic::Normals => (Dimensions::Vec3, FLOAT),
            Semantic::Joints(_) => (Dimensions::Vec4, JOINT_INDICES),
            Semantic::Weights(_) => (Dimensions::Vec4, WEIGHTS),
            Semantic::TexCoords(0) => (Dimensions::Vec2, TEX_COORDS),
            // Not read by the rig.
            _ => continue,
        };
        let what = format!("{} of {within}", semantic_name(&semantic));
        check_accessor(
            &accessor,
            &uses(what.clone(), dimensions, components),
            buffers,
        )?;
        if accessor.count() != n {
            return Err((
                format!("accessor {} ({what})", accessor.index()),
                format!(
                    "has {} elements, but POSITION (accessor {}) has {n}",
                    accessor.count(),
                    position.index()
                ),
            ));
        }
    }
    if let Some(accessor) = primitive.indices() {
        let what = format!("indices of {within}");
        check_accessor(
            &accessor,
            &uses(what, Dimensions::Scalar, UNSIGNED),
            buffers,
        )?;
    }
    Ok(n)
}

/// Every channel's target (node and property, which the `gltf` crate does not validate) and
/// its sampler's input and output accessors.
fn check_animations(
    doc: &gltf::Document,
    buffers: &[gltf::buffer::Data],
) -> Result<(), (String, String)> {
    let nodes = doc.nodes().len();
    let mut keys = 0usize;
    for (a, animation) in doc.as_json().animations.iter().enumerate() {
        let animation_item = item("animation", a, animation.name.as_deref());
        for (c, channel) in animation.channels.iter().enumerate() {
            let channel_item = format!("{animation_item} channel {c}");
            let node = channel.target.node.value();
            if node >= nodes {
                return Err((
                    channel_item,
                    format!("targets node {node}, but the file has {nodes} nodes"),
                ));
            }
            let Checked::Valid(property) = channel.target.path else {
                return Err((
                    channel_item,
                    "targets an unknown property: glTF allows translation, rotation, scale or \
                     weights"
                        .into(),
                ));
            };
            let sampler = &animation.samplers[channel.sampler.value()];
            let accessor = |index: usize| {
                doc.accessors()
                    .nth(index)
                    .unwrap_or_else(|| unreachable!("validated by the gltf crate"))
            };
            let input = accessor(sampler.input.value());
            let what = format!("{channel_item} input (key times)");
            check_accessor(&input, &uses(what, Dimensions::Scalar, FLOAT), buffers)?;
            let output = accessor(sampler.output.value());
            let (dimensions, components) = match property {
                Property::Translation | Property::Scale => (Dimensions::Vec3, FLOAT),
                Property::Rotation => (Dimensions::Vec4, FLOAT_OR_NORMALIZED),
                Property::MorphTargetWeights => (Dimensions::Scalar, FLOAT_OR_NORMALIZED),
            };
            let what = format!("{channel_item} output ({})", property_name(property));
            check_accessor(&output, &uses(what, dimensions, components), buffers)?;
            keys = keys
                .saturating_add(input.count())
                .saturating_add(output.count());
        }
    }
    if keys > MAX_KEYS {
        return Err((
            "animations".into(),
            format!(
                "{keys} key times and values in all, more than the {MAX_KEYS} the reader takes"
            ),
        ));
    }
    Ok(())
}

/// Type, component type and bytes of one accessor read as `usage`.
fn check_accessor(
    accessor: &gltf::Accessor,
    usage: &Use,
    buffers: &[gltf::buffer::Data],
) -> Result<(), (String, String)> {
    let item = format!("accessor {} ({})", accessor.index(), usage.what);
    let found = (accessor.data_type(), accessor.normalized());
    if accessor.dimensions() != usage.dimensions || !usage.components.contains(&found) {
        let allowed: Vec<String> = usage
            .components
            .iter()
            .map(|&c| component_name(c))
            .collect();
        return Err((
            item,
            format!(
                "is {} of {}, but glTF 2.0 allows only {} of {}",
                type_name(accessor.dimensions()),
                component_name(found),
                type_name(usage.dimensions),
                or_list(&allowed)
            ),
        ));
    }
    check_bytes(accessor, buffers).map_err(|problem| (item, problem))
}

/// The accessor's elements (and its sparse indices and values) lie inside their buffer views,
/// and those inside their buffers; sparse indices increase strictly and stay below `count`.
fn check_bytes(accessor: &gltf::Accessor, buffers: &[gltf::buffer::Data]) -> Result<(), String> {
    let count = accessor.count();
    if count == 0 {
        return Err("has count 0: glTF requires at least one element".into());
    }
    let size = accessor.size();
    if let Some(view) = accessor.view() {
        elements(&view, accessor.offset(), count, size, "its")?;
    }
    let Some(sparse) = accessor.sparse() else {
        return Ok(());
    };
    let sparse_count = sparse.count();
    if sparse_count == 0 || sparse_count > count {
        return Err(format!(
            "has {sparse_count} sparse values for {count} elements: glTF needs 1 to {count}"
        ));
    }
    let indices = sparse.indices();
    let index_size = indices.index_type().size();
    let bytes = elements(
        &indices.view(),
        indices.offset(),
        sparse_count,
        index_size,
        "its sparse indices'",
    )?;
    let values = sparse.values();
    elements(
        &values.view(),
        values.offset(),
        sparse_count,
        size,
        "its sparse values'",
    )?;
    let data = &buffers[bytes.buffer].0[bytes.start..];
    let mut previous = None;
    for k in 0..sparse_count {
        let at = &data[k * bytes.stride..k * bytes.stride + index_size];
        let index = at
            .iter()
            .rev()
            .fold(0usize, |v, &b| v << 8 | usize::from(b));
        if index >= count || previous.is_some_and(|p| index <= p) {
            return Err(format!(
                "sparse index {k} is {index}: glTF requires sparse indices below the count \
                 ({count}) and strictly increasing"
            ));
        }
        previous = Some(index);
    }
    Ok(())
}

/// Where `count` elements of `size` bytes lie in the buffer.
struct Span {
    buffer: usize,
    start: usize,
    stride: usize,
}

/// Checks that `count ≥ 1` elements of `size` bytes from `offset` in `view` (at its stride)
/// lie inside the view, and the view inside its buffer. `whose` names the view in messages.
fn elements(
    view: &gltf::buffer::View,
    offset: usize,
    count: usize,
    size: usize,
    whose: &str,
) -> Result<Span, String> {
    let buffer = view.buffer();
    let view_end = view.offset().checked_add(view.length());
    if view_end.is_none_or(|end| end > buffer.length()) {
        return Err(format!(
            "{whose} buffer view {} (bytes {} + {}) runs past the end of buffer {} ({} bytes)",
            view.index(),
            view.offset(),
            view.length(),
            buffer.index(),
            buffer.length()
        ));
    }
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(format!(
            "{whose} buffer view {} has byteStride {stride}, less than the {size}-byte element",
            view.index()
        ));
    }
    let end = (count - 1)
        .checked_mul(stride)
        .and_then(|n| n.checked_add(offset))
        .and_then(|n| n.checked_add(size));
    if end.is_none_or(|end| end > view.length()) {
        return Err(format!(
            "{count} elements of {size} bytes from byte {offset} do not fit in {whose} buffer \
             view {} ({} bytes)",
            view.index(),
            view.length()
        ));
    }
    Ok(Span {
        buffer: buffer.index(),
        start: view.offset() + offset,
        stride,
    })
}

fn semantic_name(semantic: &Semantic) -> String {
    match semantic {
        Semantic::Positions => "POSITION".into(),
        Semantic::Normals => "NORMAL".into(),
        Semantic::Joints(set) => format!("JOINTS_{set}"),
        Semantic::Weights(set) => format!("WEIGHTS_{set}"),
        Semantic::TexCoords(set) => format!("TEXCOORD_{set}"),
        other => format!("{other:?}"),
    }
}

fn property_name(property: Property) -> &'static str {
    match property {
        Property::Translation => "translation",
        Property::Rotation => "rotation",
        Property::Scale => "scale",
        Property::MorphTargetWeights => "weights",
    }
}

/// glTF's name of an accessor type.
pub fn type_name(dimensions: Dimensions) -> &'static str {
    match dimensions {
        Dimensions::Scalar => "SCALAR",
        Dimensions::Vec2 => "VEC2",
        Dimensions::Vec3 => "VEC3",
        Dimensions::Vec4 => "VEC4",
        Dimensions::Mat2 => "MAT2",
        Dimensions::Mat3 => "MAT3",
        Dimensions::Mat4 => "MAT4",
    }
}

fn component_name((data_type, normalized): Component) -> String {
    let name = match data_type {
        DataType::I8 => "BYTE",
        DataType::U8 => "UNSIGNED_BYTE",
        DataType::I16 => "SHORT",
        DataType::U16 => "UNSIGNED_SHORT",
        DataType::U32 => "UNSIGNED_INT",
        DataType::F32 => "FLOAT",
    };
    if normalized {
        format!("normalized {name}")
    } else {
        name.to_owned()
    }
}

/// `a`, `a or b`, `a, b or c`.
fn or_list(items: &[String]) -> String {
    match items {
        [] => String::new(),
        [one] => one.clone(),
        [rest @ .., last] => format!("{} or {last}", rest.join(", ")),
    }
}
