//! From the bytes of a `.gltf` or `.glb` to a validated document and its buffers, with every
//! failure named in the file's terms: the GLB header or chunk that is cut short, the JSON that
//! does not parse (line and column), the JSON path the `gltf` crate's validation refuses, the
//! buffer and the external file that cannot be read.
//!
//! The `gltf` crate's own entry points are not used for this: `Gltf::open` reads a GLB by the
//! length its header claims (allocating that much before finding the file short, then saying
//! only "failed to fill whole buffer"), its validation indexes the accessors with a
//! primitive's `POSITION` before checking that index, and `import_buffers` reads any file or
//! device an URI names, whole, and reports a missing one without its name.

use std::path::{Path, PathBuf};

use gltf::buffer::Source;
use gltf::json;

use super::GltfError;
use crate::input::{InputKind, read_at_most};

/// A validated document and the bytes of each of its buffers (at least `byteLength` each).
pub struct Loaded {
    pub document: gltf::Document,
    pub buffers: Vec<gltf::buffer::Data>,
}

/// Parses `bytes` (the contents of `path`, which messages name). External buffers are read
/// relative to `base`; without a base they are an error.
pub fn parse(bytes: &[u8], path: &Path, base: Option<&Path>) -> Result<Loaded, GltfError> {
    let malformed = |problem: String| GltfError::Malformed {
        path: path.to_path_buf(),
        problem,
    };
    let (text, blob) = split(bytes).map_err(malformed)?;
    let root: json::Root = json::deserialize::from_slice(text).map_err(|e| {
        let part = if bytes.starts_with(b"glTF") {
            "its JSON chunk is"
        } else {
            "it is"
        };
        malformed(format!("{part} not valid glTF JSON: {e}"))
    })?;
    check_positions(&root, path)?;
    let document = gltf::Document::from_json(root).map_err(|e| match e {
        gltf::Error::Validation(errors) => {
            let (item, error) = &errors[0];
            let more = match errors.len() {
                1 => String::new(),
                2 => " (and 1 more problem)".into(),
                n => format!(" (and {} more problems)", n - 1),
            };
            GltfError::Invalid {
                path: path.to_path_buf(),
                item: item.to_string(),
                problem: format!("{}{more}", validation_problem(*error)),
            }
        }
        other => malformed(other.to_string()),
    })?;
    check_version(document.as_json(), path)?;
    let buffers = load_buffers(&document, blob, base, path)?;
    Ok(Loaded { document, buffers })
}

/// The JSON of a document and its binary chunk: a `.glb`'s chunks (from the magic `glTF`), or a
/// `.gltf`'s text and none.
pub(crate) fn split(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), String> {
    if bytes.starts_with(b"glTF") {
        split_glb(bytes)
    } else {
        Ok((json_text(bytes)?, None))
    }
}

/// The JSON chunk and the BIN chunk (if any) of a GLB file, every length checked against the
/// bytes there are.
fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), String> {
    let len = bytes.len();
    let word = |at: usize| -> Option<u32> {
        let b = bytes.get(at..at + 4)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Err(format!(
            "truncated GLB: {len} bytes, shorter than the 12-byte header"
        ));
    };
    if version != 2 {
        return Err(format!(
            "GLB container version {version}: only version 2 (glTF 2.0) is supported"
        ));
    }
    if length as usize != len {
        let cut = if (length as usize) > len {
            "truncated GLB: "
        } else {
            ""
        };
        return Err(format!(
            "{cut}the GLB header says the file has {length} bytes, it has {len}"
        ));
    }
    let chunk = |at: usize, name: &str| -> Result<(&[u8], [u8; 4], usize), String> {
        let (Some(size), Some(kind)) = (word(at), bytes.get(at + 4..at + 8)) else {
            return Err(format!(
                "truncated GLB: the {name} chunk's 8-byte header at byte {at} runs past the end"
            ));
        };
        let start = at + 8;
        let end = start
            .checked_add(size as usize)
            .filter(|&end| end <= len)
            .ok_or_else(|| {
                format!(
                    "truncated GLB: the {name} chunk says {size} bytes, {} follow its header",
                    len - start
                )
            })?;
        let kind = [kind[0], kind[1], kind[2], kind[3]];
        Ok((&bytes[start..end], kind, end))
    };
    let (json_chunk, kind, end) = chunk(12, "JSON")?;
    if &kind != b"JSON" {
        return Err(format!(
            "the first GLB chunk is {:?}, glTF requires the JSON chunk first",
            String::from_utf8_lossy(&kind)
        ));
    }
    // A BIN chunk may follow; chunks of other (extension) types are ignored, as the
    // specification requires of clients.
    let mut blob = None;
    let mut at = end;
    while at < len {
        let (data, kind, end) = chunk(at, "second")?;
        if &kind == b"BIN\0" && blob.is_none() {
            blob = Some(data);
        }
        at = end;
    }
    Ok((json_text(json_chunk)?, blob))
}

/// The JSON text of a document without a leading UTF-8 byte-order mark, refused when it is
/// empty or is not a JSON object.
fn json_text(bytes: &[u8]) -> Result<&[u8], String> {
    let text = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    match text.iter().find(|b| !b.is_ascii_whitespace()) {
        None if bytes.is_empty() => Err("the file is empty, not a glTF document".into()),
        None => Err("the file holds only white space, not a glTF document".into()),
        Some(b'{') => Ok(text),
        Some(b'[') => Err(
            "not a glTF document: its JSON is an array, glTF is a JSON object with an \"asset\""
                .into(),
        ),
        Some(_) => Err(
            "not a glTF document: it does not start with a JSON object (`{`) or the GLB magic \
             `glTF`"
                .into(),
        ),
    }
}

/// What the `gltf` crate's validation found, in the file's terms.
fn validation_problem(error: json::validation::Error) -> &'static str {
    use json::validation::Error;
    match error {
        Error::IndexOutOfBounds => "names an item the file does not have",
        Error::Invalid => "has a value glTF 2.0 does not allow",
        Error::Missing => "is missing, and glTF 2.0 requires it",
        Error::Oversize => "is too large for this machine",
        Error::Unsupported => "names a required extension this reader does not support",
    }
}

/// The checks the `gltf` crate's validation assumes: every primitive's `POSITION` names an
/// accessor that exists, of type VEC3 (its validation indexes that accessor, then reads its
/// bounds as three numbers, before checking either).
fn check_positions(root: &json::Root, path: &Path) -> Result<(), GltfError> {
    use json::validation::Checked;
    let position = Checked::Valid(json::mesh::Semantic::Positions);
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let Some(index) = primitive.attributes.get(&position) else {
                continue;
            };
            let mesh_item = super::item("mesh", m, mesh.name.as_deref());
            let within = format!("POSITION of {mesh_item} primitive {p}");
            let refuse = |item: String, problem: String| GltfError::Invalid {
                path: path.to_path_buf(),
                item,
                problem,
            };
            let Some(accessor) = root.accessors.get(index.value()) else {
                return Err(refuse(
                    within,
                    format!(
                        "names accessor {}, but the file has {} accessors",
                        index.value(),
                        root.accessors.len()
                    ),
                ));
            };
            if let Checked::Valid(dimensions) = accessor.type_
                && dimensions != json::accessor::Type::Vec3
            {
                return Err(refuse(
                    format!("accessor {} ({within})", index.value()),
                    format!(
                        "is {}, but glTF 2.0 allows only VEC3 of FLOAT",
                        super::spec::type_name(dimensions)
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// glTF 2.x only: `asset.version` (and `minVersion`, when given) must have major version 2.
fn check_version(root: &json::Root, path: &Path) -> Result<(), GltfError> {
    let asset = &root.asset;
    let major = |v: &str| v.split('.').next().and_then(|m| m.parse::<u32>().ok());
    let refuse = |field: &str, value: &str| GltfError::Invalid {
        path: path.to_path_buf(),
        item: format!("asset.{field}"),
        problem: format!("is {value:?}: only glTF 2.0 files can be read"),
    };
    if major(&asset.version) != Some(2) {
        return Err(refuse("version", &asset.version));
    }
    if let Some(min) = &asset.min_version
        && (major(min) != Some(2) || min.split('.').nth(1).is_some_and(|m| m != "0"))
    {
        return Err(refuse("minVersion", min));
    }
    Ok(())
}

/// Each buffer's bytes: the GLB's BIN chunk, a `data:` URI, or an external file (read up to
/// `byteLength`, which it must hold).
fn load_buffers(
    document: &gltf::Document,
    blob: Option<&[u8]>,
    base: Option<&Path>,
    path: &Path,
) -> Result<Vec<gltf::buffer::Data>, GltfError> {
    let invalid = |item: &str, problem: String| GltfError::Invalid {
        path: path.to_path_buf(),
        item: item.to_owned(),
        problem,
    };
    let mut buffers = Vec::new();
    for buffer in document.buffers() {
        let item = super::item("buffer", buffer.index(), buffer.name());
        let data = match buffer.source() {
            Source::Bin => match blob {
                Some(blob) if buffer.index() == 0 => blob.to_vec(),
                _ => {
                    return Err(invalid(
                        &item,
                        "has no uri, so it must be the first buffer of a GLB file with a BIN \
                         chunk"
                            .into(),
                    ));
                }
            },
            Source::Uri(uri) if uri.starts_with("data:") => {
                gltf::buffer::Data::from_source(buffer.source(), None)
                    .map_err(|e| invalid(&item, format!("its data: URI does not decode: {e}")))?
                    .0
            }
            Source::Uri(uri) => {
                let file = external_file(uri, base).map_err(|p| invalid(&item, p))?;
                read_at_most(&file, InputKind::GltfBuffer, buffer.length() as u64).map_err(
                    |source| GltfError::Buffer {
                        path: path.to_path_buf(),
                        buffer: item.clone(),
                        source,
                    },
                )?
            }
        };
        if data.len() < buffer.length() {
            return Err(invalid(
                &item,
                format!(
                    "holds {} bytes, but its byteLength is {}",
                    data.len(),
                    buffer.length()
                ),
            ));
        }
        buffers.push(gltf::buffer::Data(data));
    }
    Ok(buffers)
}

/// The file a buffer's URI names: a path relative to `base` (percent-encoded) or a `file:` URI.
pub(crate) fn external_file(uri: &str, base: Option<&Path>) -> Result<PathBuf, String> {
    let Some(base) = base else {
        return Err(format!(
            "names the external file {uri:?}, but the document was not read from a directory"
        ));
    };
    if let Some(file) = uri
        .strip_prefix("file://")
        .or_else(|| uri.strip_prefix("file:"))
    {
        return Ok(PathBuf::from(file));
    }
    if uri.contains(':') {
        return Err(format!(
            "its uri {uri:?} has an unsupported scheme: only data: URIs and files can be read"
        ));
    }
    let decoded = urlencoding::decode(uri).map_err(|_| {
        format!("its uri {uri:?} is not a valid percent-encoded UTF-8 relative path")
    })?;
    Ok(base.join(decoded.as_ref()))
}
