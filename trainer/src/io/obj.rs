//! Wavefront OBJ reader that keeps the file's vertex order.
//!
//! Per-vertex outputs (transfer, model rows) are matched to the artist's mesh by index, so the
//! `i`-th vertex of the returned [`Mesh`] must be the `i`-th `v` line of the file. `tobj` (the
//! general-purpose OBJ crate) re-indexes vertices by first use in the faces
//! when it unifies attribute indices, which silently breaks that contract; this reader is
//! deliberately small instead. Only geometry and texture coordinates are read: `v`, `vn`, `vt`
//! and `f` statements (corner forms `v`, `v/vt`, `v/vt/vn`, `v//vn`, negative relative
//! indices, polygons fan-triangulated). Every other statement (`o`, `g`, `s`, `usemtl`, `l`,
//! …) is ignored.
//!
//! Texture coordinates become a [`UvLayout`] (per triangle corner, for SH light maps) when
//! every face corner names one. OBJ's `v` points up (OpenGL's texture origin at the bottom
//! left); the layout follows glTF's, `v` down, so it holds `1 − v`.

use crate::input::{InputKind, read_input_text};
use crate::rig::mesh::{Mesh, area_weighted_normals};
use crate::rig::uv::UvLayout;
use glam::DVec3;
use std::path::{Path, PathBuf};

/// Why an OBJ file could not be read. Every variant names the file; line errors name the line.
#[derive(Debug, thiserror::Error)]
pub enum ObjError {
    /// The file could not be read (the error names it and why).
    #[error(transparent)]
    Io(#[from] crate::input::InputError),
    /// A statement is malformed or references something that does not exist.
    #[error("{}:{line}: {kind}", path.display())]
    Line {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong on that line.
        kind: LineError,
    },
    /// The file has no `v` statement.
    #[error("{}: no vertices", path.display())]
    NoVertices {
        /// The file.
        path: PathBuf,
    },
    /// The file has vertices but no `f` statement.
    #[error("{}: no faces", path.display())]
    NoFaces {
        /// The file.
        path: PathBuf,
    },
}

/// What is wrong with one line of an OBJ file.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum LineError {
    /// A coordinate or index is not a number.
    #[error("malformed number {}", crate::text::quote(.0))]
    MalformedNumber(String),
    /// A coordinate is NaN or infinite (including values that overflow f32).
    #[error("coordinate {} is not finite", crate::text::quote(.0))]
    NonFinite(String),
    /// A `v` or `vn` statement has fewer than three coordinates.
    #[error("expected 3 coordinates, found {0}")]
    TooFewCoordinates(usize),
    /// A `vt` statement without coordinates.
    #[error("a texture coordinate needs at least u")]
    EmptyTexCoord,
    /// A face has fewer than three corners.
    #[error("a face needs at least 3 corners, found {0}")]
    TooFewCorners(usize),
    /// A face corner has more than three `/`-separated parts or no vertex index.
    #[error("malformed face corner {}", crate::text::quote(.0))]
    MalformedCorner(String),
    /// An index of 0 (OBJ indices start at 1; negative ones count back from the end).
    #[error("index 0 is invalid (OBJ indices start at 1)")]
    ZeroIndex,
    /// A face references a vertex that does not exist.
    #[error("face references vertex {index}, but only {count} vertices are available to it")]
    MissingVertex {
        /// The index as written.
        index: i64,
        /// Vertices available to it.
        count: usize,
    },
    /// A face references a texture coordinate that does not exist.
    #[error("face references texture coordinate {index}, but only {count} are available to it")]
    MissingTexCoord {
        /// The index as written.
        index: i64,
        /// Texture coordinates available to it.
        count: usize,
    },
    /// A face references a normal that does not exist.
    #[error("face references normal {index}, but only {count} normals are available to it")]
    MissingNormal {
        /// The index as written.
        index: i64,
        /// Normals available to it.
        count: usize,
    },
}

/// Reads an OBJ file into a [`Mesh`] whose vertices are the file's `v` lines, in order.
///
/// Normals: a vertex referenced by face corners with normals gets the normalised average of
/// those (unit) normals; every other vertex, and every vertex of a file without `vn`, gets the
/// area-weighted normal of its faces.
pub fn read_obj(path: impl AsRef<Path>) -> Result<Mesh, ObjError> {
    let path = path.as_ref();
    let text = read_input_text(path, InputKind::Obj)?;
    parse_obj(&text, path)
}

/// Reads an OBJ file as [`read_obj`] does, with its texture coordinates as a layout per
/// triangle corner (`None` unless every face corner has a `vt`; see the module docs).
pub fn read_obj_with_uvs(path: impl AsRef<Path>) -> Result<(Mesh, Option<UvLayout>), ObjError> {
    let path = path.as_ref();
    let text = read_input_text(path, InputKind::Obj)?;
    parse_obj_with_uvs(&text, path)
}

/// One face corner as written: vertex index and optional normal index, with the counts in
/// effect on its line (negative indices are relative to those).
struct Corner {
    vertex: i64,
    texcoord: Option<i64>,
    normal: Option<i64>,
}

/// A face and where it was written.
struct Face {
    line: usize,
    corners: Vec<Corner>,
    vertices_so_far: usize,
    texcoords_so_far: usize,
    normals_so_far: usize,
}

/// Parses OBJ text; `path` is only used in error messages. See [`read_obj`]. A leading UTF-8
/// byte-order mark is skipped (left in, it would hide the first statement and shift every
/// face index after it).
pub fn parse_obj(text: &str, path: &Path) -> Result<Mesh, ObjError> {
    parse_obj_with_uvs(text, path).map(|(mesh, _)| mesh)
}

/// Parses OBJ text with its texture coordinates; see [`read_obj_with_uvs`].
pub fn parse_obj_with_uvs(text: &str, path: &Path) -> Result<(Mesh, Option<UvLayout>), ObjError> {
    let text = crate::text::without_bom(text);
    let at = |line: usize| {
        move |kind: LineError| ObjError::Line {
            path: path.to_owned(),
            line,
            kind,
        }
    };
    let mut positions: Vec<[f32; 3]> = Vec::new();
    let mut file_normals: Vec<DVec3> = Vec::new();
    let mut texcoords: Vec<[f32; 2]> = Vec::new();
    let mut faces: Vec<Face> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let content = raw.split('#').next().unwrap_or("");
        let mut words = content.split_whitespace();
        match words.next() {
            Some("v") => positions.push(parse_xyz(words).map_err(at(line))?),
            Some("vt") => texcoords.push(parse_uv(words).map_err(at(line))?),
            Some("vn") => {
                let n = parse_xyz(words).map_err(at(line))?;
                file_normals.push(DVec3::from(n.map(f64::from)).normalize_or_zero());
            }
            Some("f") => {
                let corners = words
                    .map(parse_corner)
                    .collect::<Result<Vec<_>, _>>()
                    .map_err(at(line))?;
                if corners.len() < 3 {
                    return Err(at(line)(LineError::TooFewCorners(corners.len())));
                }
                faces.push(Face {
                    line,
                    corners,
                    vertices_so_far: positions.len(),
                    texcoords_so_far: texcoords.len(),
                    normals_so_far: file_normals.len(),
                });
            }
            _ => {}
        }
    }
    if positions.is_empty() {
        return Err(ObjError::NoVertices {
            path: path.to_owned(),
        });
    }
    if faces.is_empty() {
        return Err(ObjError::NoFaces {
            path: path.to_owned(),
        });
    }

    let mut triangles = Vec::new();
    let mut corner_uvs: Option<Vec<[[f32; 2]; 3]>> = Some(Vec::new());
    let mut normal_sums = vec![DVec3::ZERO; positions.len()];
    for face in &faces {
        let mut resolved = Vec::with_capacity(face.corners.len());
        for corner in &face.corners {
            let v = resolve(corner.vertex, face.vertices_so_far, positions.len())
                .ok_or(LineError::MissingVertex {
                    index: corner.vertex,
                    count: available(corner.vertex, face.vertices_so_far, positions.len()),
                })
                .map_err(at(face.line))?;
            if let Some(n) = corner.normal {
                let k = resolve(n, face.normals_so_far, file_normals.len())
                    .ok_or(LineError::MissingNormal {
                        index: n,
                        count: available(n, face.normals_so_far, file_normals.len()),
                    })
                    .map_err(at(face.line))?;
                normal_sums[v as usize] += file_normals[k as usize];
            }
            let uv = corner
                .texcoord
                .map(|t| {
                    resolve(t, face.texcoords_so_far, texcoords.len())
                        .map(|k| texcoords[k as usize])
                        .ok_or(LineError::MissingTexCoord {
                            index: t,
                            count: available(t, face.texcoords_so_far, texcoords.len()),
                        })
                })
                .transpose()
                .map_err(at(face.line))?;
            resolved.push((v, uv));
        }
        for k in 1..resolved.len() - 1 {
            let [a, b, c] = [resolved[0], resolved[k], resolved[k + 1]];
            triangles.push([a.0, b.0, c.0]);
            corner_uvs = corner_uvs.and_then(|mut uvs| {
                uvs.push([a.1?, b.1?, c.1?]);
                Some(uvs)
            });
        }
    }

    let mut fallback: Option<Vec<[f32; 3]>> = None;
    let normals = normal_sums
        .iter()
        .enumerate()
        .map(|(j, sum)| match sum.try_normalize() {
            Some(n) => n.as_vec3().to_array(),
            None => {
                fallback.get_or_insert_with(|| area_weighted_normals(&positions, &triangles))[j]
            }
        })
        .collect();
    let mesh = Mesh {
        positions,
        normals,
        triangles,
    };
    Ok((mesh, corner_uvs.map(|corners| UvLayout { corners })))
}

/// A `vt` statement's `u` and `v` (`v` defaults to 0; a `w` must be a number but is ignored),
/// as the layout stores it: `[u, 1 − v]` (see the module docs).
fn parse_uv<'a>(words: impl Iterator<Item = &'a str>) -> Result<[f32; 2], LineError> {
    let (uv, count) = parse_numbers::<2>(words)?;
    if count == 0 {
        return Err(LineError::EmptyTexCoord);
    }
    Ok([uv[0], 1.0 - uv[1]])
}

/// The first three coordinates of a `v`/`vn` statement; extra values (`w`, vertex colours)
/// must still be numbers but are ignored.
fn parse_xyz<'a>(words: impl Iterator<Item = &'a str>) -> Result<[f32; 3], LineError> {
    let (xyz, count) = parse_numbers::<3>(words)?;
    if count < 3 {
        return Err(LineError::TooFewCoordinates(count));
    }
    Ok(xyz)
}

/// The first `N` of a statement's numbers (zero where there are fewer) and how many it has;
/// every one must be a finite number.
fn parse_numbers<'a, const N: usize>(
    words: impl Iterator<Item = &'a str>,
) -> Result<([f32; N], usize), LineError> {
    let mut out = [0.0f32; N];
    let mut count = 0;
    for word in words {
        let value: f32 = word
            .parse()
            .map_err(|_| LineError::MalformedNumber(word.to_owned()))?;
        if !value.is_finite() {
            return Err(LineError::NonFinite(word.to_owned()));
        }
        if count < N {
            out[count] = value;
        }
        count += 1;
    }
    Ok((out, count))
}

/// `v`, `v/vt`, `v/vt/vn` or `v//vn`.
fn parse_corner(word: &str) -> Result<Corner, LineError> {
    let parts: Vec<&str> = word.split('/').collect();
    if parts.len() > 3 || parts[0].is_empty() {
        return Err(LineError::MalformedCorner(word.to_owned()));
    }
    let index = |s: &str| -> Result<i64, LineError> {
        match s.parse::<i64>() {
            Ok(0) => Err(LineError::ZeroIndex),
            Ok(i) => Ok(i),
            Err(_) => Err(LineError::MalformedNumber(s.to_owned())),
        }
    };
    let vertex = index(parts[0])?;
    let texcoord = parts
        .get(1)
        .filter(|s| !s.is_empty())
        .map(|s| index(s))
        .transpose()?;
    let normal = parts.get(2).map(|s| index(s)).transpose()?;
    Ok(Corner {
        vertex,
        texcoord,
        normal,
    })
}

/// 0-based index of a 1-based (`> 0`) or relative (`< 0`, counted back from the elements
/// defined before the face) OBJ index, if it exists. Positive indices may refer to elements
/// defined later in the file, as most exporters and readers allow.
fn resolve(index: i64, so_far: usize, total: usize) -> Option<u32> {
    let zero_based = if index < 0 {
        so_far as i64 + index
    } else {
        index - 1
    };
    if zero_based < 0 || zero_based as u64 >= total as u64 {
        return None;
    }
    u32::try_from(zero_based).ok()
}

/// How many elements an index could refer to: those defined before the face for a relative
/// index, all of them for an absolute one.
fn available(index: i64, so_far: usize, total: usize) -> usize {
    if index < 0 { so_far } else { total }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Mesh, ObjError> {
        parse_obj(text, Path::new("test.obj"))
    }

    fn line_error(text: &str) -> (usize, LineError) {
        match parse(text) {
            Err(ObjError::Line { line, kind, path }) => {
                assert_eq!(path, Path::new("test.obj"));
                (line, kind)
            }
            other => panic!("expected a line error, got {other:?}"),
        }
    }

    #[test]
    fn vertex_order_is_the_order_of_v_lines() {
        // Faces reference the vertices in reverse and scrambled order; tobj would renumber them
        // 0, 1, 2, … by first use.
        let text = "# square\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 9 9 9\nf 4 3 1\nf 3 2 1\n";
        let mesh = parse(text).unwrap();
        assert_eq!(
            mesh.positions,
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
                [9.0, 9.0, 9.0]
            ]
        );
        assert_eq!(mesh.triangles, vec![[3, 2, 0], [2, 1, 0]]);
        // Unreferenced vertex 5 is kept (an isolated vertex, +z normal).
        assert_eq!(mesh.normals.len(), 5);
    }

    #[test]
    fn every_corner_form_and_polygon_fans() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n\
                    f 1/1/1 2/2/1 3/3/1\nf 1//1 3//1 4//1\nf 1/1 2/2 3/3\nf -4 -3 -2 -1\no thing\ns off\ng grp\nusemtl m\n";
        let mesh = parse(text).unwrap();
        assert_eq!(
            mesh.triangles,
            vec![[0, 1, 2], [0, 2, 3], [0, 1, 2], [0, 1, 2], [0, 2, 3]]
        );
        for n in &mesh.normals {
            assert_eq!(*n, [0.0, 0.0, 1.0]);
        }
    }

    #[test]
    fn texture_coordinates_give_a_layout_per_corner_with_v_flipped() {
        let path = Path::new("test.obj");
        // A quad whose vertex 1 sits on a seam (two texture coordinates), fanned.
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0.25\nvt 1 1\nvt 0 1 0\nvt 0.5\n\
                    f 1/1 2/2 3/3 4/4\nf 1/5 3/-3 2/-4\n";
        let (mesh, layout) = parse_obj_with_uvs(text, path).unwrap();
        let layout = layout.unwrap();
        assert_eq!(mesh.triangles, [[0, 1, 2], [0, 2, 3], [0, 2, 1]]);
        assert_eq!(
            layout.corners,
            [
                [[0.0, 1.0], [1.0, 0.75], [1.0, 0.0]],
                [[0.0, 1.0], [1.0, 0.0], [0.0, 0.0]],
                [[0.5, 1.0], [1.0, 0.0], [1.0, 0.75]],
            ]
        );
        assert_eq!(
            layout.vertex_uvs(&mesh.triangles, 4)[0],
            [[0.0, 1.0], [0.5, 1.0]]
        );
        // One corner without a texture coordinate: no layout, the same mesh.
        let partial = "v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nf 1/1 2/1 3\n";
        let (mesh, layout) = parse_obj_with_uvs(partial, path).unwrap();
        assert!(layout.is_none());
        assert_eq!(mesh, parse(partial).unwrap());
        assert_eq!(
            line_error("v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nf 1/1 2/2 3/1\n"),
            (5, LineError::MissingTexCoord { index: 2, count: 1 })
        );
        assert_eq!(line_error("vt\n"), (1, LineError::EmptyTexCoord));
        assert_eq!(
            line_error("vt 0 nan\n"),
            (1, LineError::NonFinite("nan".into()))
        );
    }

    #[test]
    fn file_normals_are_averaged_per_vertex() {
        // Vertex 1 is used with +z (scaled, so normalised first) and +x: average (1,0,1)/√2.
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 5\nvn 1 0 0\nf 1//1 2//1 3//1\nf 1//2 3//2 4//2\n";
        let mesh = parse(text).unwrap();
        let h = std::f32::consts::FRAC_1_SQRT_2;
        let close = |a: [f32; 3], b: [f32; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6);
        assert!(close(mesh.normals[0], [h, 0.0, h]), "{:?}", mesh.normals[0]);
        assert!(close(mesh.normals[1], [0.0, 0.0, 1.0]));
        assert!(close(mesh.normals[3], [1.0, 0.0, 0.0]));
    }

    #[test]
    fn without_file_normals_normals_are_area_weighted() {
        let text = "v 0 0 0\nv 2 0 0\nv 0 2 0\nv 0 0 0.1\nv 0.1 0 0\nf 1 2 3\nf 1 4 5\n";
        let mesh = parse(text).unwrap();
        assert_eq!(
            mesh.normals,
            area_weighted_normals(&mesh.positions, &mesh.triangles)
        );
    }

    #[test]
    fn malformed_lines_name_the_line_and_the_problem() {
        let cases: [(&str, usize, LineError); 11] = [
            (
                "v 0 0 0\nv 1 x 0\n",
                2,
                LineError::MalformedNumber("x".into()),
            ),
            (
                "v 0 0 0\n\nv nan 0 0\n",
                3,
                LineError::NonFinite("nan".into()),
            ),
            (
                "v 0 0 0\nv 1e39 0 0\n",
                2,
                LineError::NonFinite("1e39".into()),
            ),
            ("v 0 0 inf\n", 1, LineError::NonFinite("inf".into())),
            ("v 0 0\n", 1, LineError::TooFewCoordinates(2)),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\n# c\nf 1 2 4\n",
                5,
                LineError::MissingVertex { index: 4, count: 3 },
            ),
            (
                "v 0 0 0\nv 1 0 0\nf 1 2 -3\nv 0 1 0\n",
                3,
                LineError::MissingVertex {
                    index: -3,
                    count: 2,
                },
            ),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 0 2\n",
                4,
                LineError::ZeroIndex,
            ),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//2 3//1\n",
                5,
                LineError::MissingNormal { index: 2, count: 1 },
            ),
            ("v 0 0 0\nv 1 0 0\nf 1 2\n", 3, LineError::TooFewCorners(2)),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1/1 2 3\n",
                4,
                LineError::MalformedCorner("1/1/1/1".into()),
            ),
        ];
        for (text, line, kind) in cases {
            assert_eq!(line_error(text), (line, kind), "{text:?}");
        }
        let (line, kind) = line_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3.5\n");
        assert_eq!((line, kind), (4, LineError::MalformedNumber("3.5".into())));
        let message = parse("v 0 0 0\nv 1 x 0\n").unwrap_err().to_string();
        assert!(
            message.contains("test.obj:2") && message.contains("\"x\""),
            "{message}"
        );
    }

    /// Zero-length normals. Expected: `vn 0 0 0` names no direction, so it contributes nothing
    /// to its vertices' average; a vertex whose only normals are zero (or cancel out, `+z` and
    /// `−z`) falls back to the area-weighted geometric normal instead of becoming NaN.
    #[test]
    fn zero_length_and_cancelling_normals_fall_back_to_geometry() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 0\nvn 0 0 1\nvn 0 0 -1\n\
                    f 1//1 2//1 3//2\nf 2//2 4//1 3//3\n";
        let mesh = parse(text).unwrap();
        let geometric = area_weighted_normals(&mesh.positions, &mesh.triangles);
        assert_eq!(mesh.normals[0], geometric[0]);
        assert_eq!(mesh.normals[1], [0.0, 0.0, 1.0]);
        assert_eq!(mesh.normals[2], geometric[2]);
        assert_eq!(mesh.normals[3], geometric[3]);
        assert!(mesh.normals.iter().flatten().all(|x| x.is_finite()));
    }

    /// A file saved with a UTF-8 byte-order mark. Expected: the mark is skipped, so the first
    /// `v` line is still vertex 1 (it was once lost, shifting every face by one).
    #[test]
    fn a_byte_order_mark_does_not_hide_the_first_vertex() {
        let plain = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n";
        let marked = parse(&format!("\u{feff}{plain}")).unwrap();
        assert_eq!(marked, parse(plain).unwrap());
        assert_eq!(marked.positions[0], [0.0, 0.0, 0.0]);
        assert_eq!(marked.triangles, vec![[0, 1, 2]]);
    }

    #[test]
    fn empty_files_are_rejected() {
        assert!(matches!(
            parse("# nothing\n"),
            Err(ObjError::NoVertices { .. })
        ));
        assert!(matches!(
            parse("v 0 0 0\nv 1 0 0\nv 0 1 0\n"),
            Err(ObjError::NoFaces { .. })
        ));
    }

    #[test]
    fn reads_files_and_reports_unreadable_ones() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("tri.obj");
        std::fs::write(&path, "v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\n").unwrap();
        let mesh = read_obj(&path).unwrap();
        assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
        let missing = dir.path().join("missing.obj");
        let err = read_obj(&missing).unwrap_err();
        assert!(matches!(err, ObjError::Io(_)));
        assert!(err.to_string().contains("missing.obj"), "{err}");
    }
}
