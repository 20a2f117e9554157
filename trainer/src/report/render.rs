//! A small deterministic software rasterizer for report pictures: per-vertex scalars (shading,
//! error) on a mesh, seen through an orthographic camera, written as PNG panels.
//!
//! Deterministic by construction: one thread, triangles drawn in mesh order, a pixel is
//! replaced only by a strictly nearer fragment, so the same mesh gives the same bytes
//! everywhere. Orthographic projection makes screen-space linear interpolation of depth and
//! values exact (Gouraud shading), so no perspective correction is needed.

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};
use image::{ImageEncoder, Rgb, RgbImage};

use crate::rig::mesh::Mesh;

/// Why a picture could not be made or saved.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// `values` did not have one entry per vertex.
    #[error("{values} values given for a mesh with {vertices} vertices")]
    ValueCount {
        /// Values given.
        values: usize,
        /// Vertices in the mesh.
        vertices: usize,
    },
    /// The requested image has no pixels.
    #[error("image size {width}x{height} has no pixels")]
    EmptyImage {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
    },
    /// Writing the file failed.
    #[error("writing {path}")]
    Io {
        /// The file being written.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// PNG encoding failed.
    #[error("encoding {path} as PNG")]
    Encode {
        /// The file being written.
        path: PathBuf,
        /// The underlying error.
        source: image::ImageError,
    },
}

/// Background of every panel and of the gutters between panels.
pub const BACKGROUND: Rgb<u8> = Rgb([24, 24, 28]);
/// Width in pixels of the gutter `side_by_side` puts between panels.
pub const GUTTER: u32 = 4;
/// Fraction of the image left empty around the fitted mesh on each side.
const MARGIN: f32 = 0.04;

/// Direction the orthographic camera looks from. The scene is z up; `yaw = 0, pitch = 0`
/// looks along +y, i.e. at the front of a character facing −y, with +x to the right.
/// Positive yaw orbits the camera counter-clockwise seen from above (toward +x), positive
/// pitch raises it to look down.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Rotation about z, radians.
    pub yaw: f32,
    /// Elevation, radians; ±π/2 looks straight down or up (the basis stays defined).
    pub pitch: f32,
}

impl View {
    /// The camera basis: right, up and forward (into the scene).
    fn basis(self) -> (Vec3, Vec3, Vec3) {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        let forward = Vec3::new(-sy * cp, cy * cp, -sp);
        let right = Vec3::new(cy, sy, 0.0);
        let up = right.cross(forward);
        (right, up, forward)
    }
}

/// How a per-vertex value becomes a colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Colormap {
    /// Shading: values clamped to 0..1, black to white.
    Grey,
    /// Errors: 0..`max` through Moreland's cool-warm map (blue, grey, red), whose lightness
    /// varies smoothly and symmetrically, so equal steps in error read as equal steps in
    /// colour. Values above `max` saturate to red.
    Error {
        /// Value drawn fully red.
        max: f32,
    },
}

/// Moreland's cool-warm diverging map at nine evenly spaced stops.
const COOL_WARM: [[f32; 3]; 9] = [
    [59.0, 76.0, 192.0],
    [98.0, 130.0, 234.0],
    [141.0, 176.0, 254.0],
    [184.0, 208.0, 249.0],
    [221.0, 221.0, 221.0],
    [245.0, 196.0, 173.0],
    [244.0, 154.0, 123.0],
    [222.0, 96.0, 77.0],
    [180.0, 4.0, 38.0],
];

impl Colormap {
    /// The colour of `value`. NaN draws magenta so it cannot pass for data.
    pub fn color(self, value: f32) -> Rgb<u8> {
        if value.is_nan() {
            return Rgb([255, 0, 255]);
        }
        match self {
            Colormap::Grey => {
                let g = (value.clamp(0.0, 1.0) * 255.0).round() as u8;
                Rgb([g, g, g])
            }
            Colormap::Error { max } => {
                let t = if max > 0.0 {
                    (value / max).clamp(0.0, 1.0)
                } else {
                    1.0
                };
                let x = t * (COOL_WARM.len() - 1) as f32;
                let i = (x.floor() as usize).min(COOL_WARM.len() - 2);
                let f = x - i as f32;
                let (a, b) = (COOL_WARM[i], COOL_WARM[i + 1]);
                Rgb(std::array::from_fn(|k| {
                    (a[k] + (b[k] - a[k]) * f).round() as u8
                }))
            }
        }
    }
}

/// Renders `values` (one per vertex, interpolated across triangles) on `mesh` seen from
/// `view`, scaled so the mesh's projected bounding box fills the image with a small margin
/// and keeps its aspect ratio. Both sides of every triangle are drawn; the z-buffer decides.
pub fn render_scalar(
    mesh: &Mesh,
    values: &[f32],
    view: View,
    width: u32,
    height: u32,
    colormap: Colormap,
) -> Result<RgbImage, RenderError> {
    if values.len() != mesh.vertex_count() {
        return Err(RenderError::ValueCount {
            values: values.len(),
            vertices: mesh.vertex_count(),
        });
    }
    render_with(mesh, view, width, height, |triangle, bary| {
        let t = mesh.triangles[triangle];
        let v: f32 = (0..3).map(|k| bary[k] * values[t[k] as usize]).sum();
        colormap.color(v)
    })
}

/// [`render_scalar`]'s projection and z-buffer with any colour per pixel: `shade(triangle,
/// barycentrics)` colours the visible point of `mesh.triangles[triangle]` (a texture lookup
/// at the interpolated UV, for a light map).
pub fn render_with(
    mesh: &Mesh,
    view: View,
    width: u32,
    height: u32,
    shade: impl Fn(usize, [f32; 3]) -> Rgb<u8>,
) -> Result<RgbImage, RenderError> {
    let mut image = RgbImage::from_pixel(width, height, BACKGROUND);
    let Some(screen) = project(&mesh.positions, view, width, height)? else {
        return Ok(image);
    };
    let mut depth = vec![f32::INFINITY; (width * height) as usize];
    for (index, t) in mesh.triangles.iter().enumerate() {
        let [a, b, c] = t.map(|i| screen.points[i as usize]);
        if !(a.is_finite() && b.is_finite() && c.is_finite()) {
            continue;
        }
        let area = edge(a, b, c);
        if area == 0.0 {
            continue;
        }
        let x0 = a.x.min(b.x).min(c.x).floor().max(0.0) as u32;
        let y0 = a.y.min(b.y).min(c.y).floor().max(0.0) as u32;
        let x1 = (a.x.max(b.x).max(c.x).ceil() as u32).min(width);
        let y1 = (a.y.max(b.y).max(c.y).ceil() as u32).min(height);
        for y in y0..y1 {
            for x in x0..x1 {
                let p = Vec3::new(x as f32 + 0.5, y as f32 + 0.5, 0.0);
                // Barycentrics, sign-normalised so either winding is drawn.
                let (wa, wb, wc) = (
                    edge(b, c, p) / area,
                    edge(c, a, p) / area,
                    edge(a, b, p) / area,
                );
                if wa < 0.0 || wb < 0.0 || wc < 0.0 {
                    continue;
                }
                let z = wa * a.z + wb * b.z + wc * c.z;
                let slot = &mut depth[(y * width + x) as usize];
                if z < *slot {
                    *slot = z;
                    image.put_pixel(x, y, shade(index, [wa, wb, wc]));
                }
            }
        }
    }
    Ok(image)
}

/// `points` seen from `view` on a `width`×`height` image: each point's pixel x and y (origin
/// at the top-left corner, y down) and depth (smaller is nearer), scaled so their projected
/// bounding box fills the image with a small margin and keeps its aspect ratio; `None` when
/// no point is finite.
fn project(
    points: &[[f32; 3]],
    view: View,
    width: u32,
    height: u32,
) -> Result<Option<Screen>, RenderError> {
    if width == 0 || height == 0 {
        return Err(RenderError::EmptyImage { width, height });
    }
    let (right, up, forward) = view.basis();
    let camera: Vec<Vec3> = points
        .iter()
        .map(|&p| {
            let p = Vec3::from(p);
            Vec3::new(p.dot(right), p.dot(up), p.dot(forward))
        })
        .collect();
    let (lo, hi) = camera.iter().filter(|p| p.is_finite()).fold(
        (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p.truncate()), hi.max(p.truncate())),
    );
    if lo.x > hi.x {
        return Ok(None);
    }
    let size = Vec2::new(width as f32, height as f32);
    let extent = (hi - lo).max(Vec2::splat(f32::EPSILON));
    let scale = ((1.0 - 2.0 * MARGIN) * size / extent).min_element();
    let centre = 0.5 * (lo + hi);
    let points = camera
        .iter()
        .map(|p| {
            Vec3::new(
                0.5 * size.x + (p.x - centre.x) * scale,
                0.5 * size.y - (p.y - centre.y) * scale,
                p.z,
            )
        })
        .collect();
    Ok(Some(Screen { points, scale }))
}

/// Points on the screen ([`project`]): pixel x, y and depth, and pixels per world unit.
struct Screen {
    points: Vec<Vec3>,
    scale: f32,
}

/// Points of a surface drawn as discs facing the camera, nearest first through a z-buffer:
/// point `i` at `positions[i]` with world radius `radii[i]` (at least the pixel it falls in)
/// and colour `colour(i)`, framed as [`render_scalar`] frames a mesh. Dense enough, the discs
/// cover the surface, and each pixel shows the one point nearest the camera there: a value
/// that varies inside a triangle shows as it is, not as its corners' blend. Ties keep the
/// earlier point, so the picture is deterministic.
pub fn render_splats(
    positions: &[[f32; 3]],
    radii: &[f32],
    view: View,
    (width, height): (u32, u32),
    colour: impl Fn(usize) -> Rgb<u8>,
) -> Result<RgbImage, RenderError> {
    if radii.len() != positions.len() {
        return Err(RenderError::ValueCount {
            values: radii.len(),
            vertices: positions.len(),
        });
    }
    let mut image = RgbImage::from_pixel(width, height, BACKGROUND);
    let Some(screen) = project(positions, view, width, height)? else {
        return Ok(image);
    };
    let mut depth = vec![f32::INFINITY; (width * height) as usize];
    for (i, (p, &radius)) in screen.points.iter().zip(radii).enumerate() {
        if !p.is_finite() {
            continue;
        }
        let r = (radius * screen.scale).max(0.5);
        let x0 = (p.x - r).floor().max(0.0) as u32;
        let y0 = (p.y - r).floor().max(0.0) as u32;
        let x1 = ((p.x + r).ceil().max(0.0) as u32).min(width);
        let y1 = ((p.y + r).ceil().max(0.0) as u32).min(height);
        for y in y0..y1 {
            for x in x0..x1 {
                let (dx, dy) = (x as f32 + 0.5 - p.x, y as f32 + 0.5 - p.y);
                let inside = dx * dx + dy * dy <= r * r;
                let own_pixel = x == p.x as u32 && y == p.y as u32;
                let slot = &mut depth[(y * width + x) as usize];
                if (inside || own_pixel) && p.z < *slot {
                    *slot = p.z;
                    image.put_pixel(x, y, colour(i));
                }
            }
        }
    }
    Ok(image)
}

/// Twice the signed area of `(a, b, p)` in screen x/y.
fn edge(a: Vec3, b: Vec3, p: Vec3) -> f32 {
    (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x)
}

/// Lambertian shading `max(0, n·l)` per vertex for a directional light toward `to_light`:
/// the quick look used to check geometry, not the PRT result.
pub fn lambert(mesh: &Mesh, to_light: Vec3) -> Vec<f32> {
    let l = to_light.normalize_or_zero();
    mesh.normals
        .iter()
        .map(|&n| Vec3::from(n).dot(l).max(0.0))
        .collect()
}

/// Panels left to right, top-aligned, separated by `GUTTER` pixels of background; shorter
/// panels are padded with background. No panels give an empty image.
pub fn side_by_side(panels: &[RgbImage]) -> RgbImage {
    if panels.is_empty() {
        return RgbImage::new(0, 0);
    }
    let height = panels.iter().map(|p| p.height()).max().unwrap_or(0);
    let width = panels.iter().map(|p| p.width()).sum::<u32>() + GUTTER * (panels.len() as u32 - 1);
    let mut out = RgbImage::from_pixel(width, height, BACKGROUND);
    let mut x = 0;
    for panel in panels {
        image::imageops::replace(&mut out, panel, i64::from(x), 0);
        x += panel.width() + GUTTER;
    }
    out
}

/// Writes `image` as a PNG at `path` atomically (see [`crate::io::atomic::write_atomic`]), so
/// readers never see a partial picture.
pub fn save_png_atomic(path: &Path, image: &RgbImage) -> Result<(), RenderError> {
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(
            image.as_raw(),
            image.width(),
            image.height(),
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|source| RenderError::Encode {
            path: path.to_path_buf(),
            source,
        })?;
    crate::io::atomic::write_atomic(path, &png).map_err(|source| RenderError::Io {
        path: path.to_path_buf(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle(depth: f32, offset: f32) -> (Vec<[f32; 3]>, [u32; 3]) {
        (
            vec![
                [offset, depth, 0.0],
                [offset + 1.0, depth, 0.0],
                [offset, depth, 1.0],
            ],
            [0, 1, 2],
        )
    }

    #[test]
    fn a_front_facing_triangle_covers_the_pixels_inside_it() {
        // Right isosceles triangle in the xz plane facing the default camera. With a 100×100
        // image the 1×1 box maps to 92×92 pixels starting at pixel 4.
        let (positions, t) = triangle(0.0, 0.0);
        let mesh = Mesh::with_area_weighted_normals(positions, vec![t]);
        let image = render_scalar(
            &mesh,
            &[1.0; 3],
            View {
                yaw: 0.0,
                pitch: 0.0,
            },
            100,
            100,
            Colormap::Grey,
        )
        .unwrap();
        let mut covered = 0;
        for (x, y, p) in image.enumerate_pixels() {
            let (u, v) = (
                (x as f32 + 0.5 - 4.0) / 92.0,
                (96.0 - (y as f32 + 0.5)) / 92.0,
            );
            let inside = u >= 0.0 && v >= 0.0 && u + v <= 1.0;
            let strictly = u > 0.01 && v > 0.01 && u + v < 0.99;
            let outside = u < -0.01 || v < -0.01 || u + v > 1.01;
            if strictly {
                assert_eq!(*p, Rgb([255; 3]), "pixel {x},{y} inside");
            }
            if outside {
                assert_eq!(*p, BACKGROUND, "pixel {x},{y} outside");
            }
            covered += usize::from(inside && *p != BACKGROUND);
        }
        // Half of 92² pixels, give or take the diagonal.
        assert!(
            (covered as i32 - 92 * 92 / 2).abs() < 92,
            "covered {covered}"
        );
    }

    #[test]
    fn the_z_buffer_keeps_the_nearer_triangle_whatever_the_order() {
        // Two identical triangles, one 1 unit nearer the camera (smaller y), drawn in both
        // orders; they share their projected footprint.
        for near_first in [true, false] {
            let (mut positions, _) = triangle(if near_first { -1.0 } else { 1.0 }, 0.0);
            positions.extend(triangle(if near_first { 1.0 } else { -1.0 }, 0.0).0);
            let near_value = if near_first {
                [1.0, 1.0, 1.0, 0.0, 0.0, 0.0]
            } else {
                [0.0, 0.0, 0.0, 1.0, 1.0, 1.0]
            };
            let mesh = Mesh::with_area_weighted_normals(positions, vec![[0, 1, 2], [3, 4, 5]]);
            let image = render_scalar(
                &mesh,
                &near_value,
                View {
                    yaw: 0.0,
                    pitch: 0.0,
                },
                64,
                64,
                Colormap::Grey,
            )
            .unwrap();
            assert_eq!(
                *image.get_pixel(20, 40),
                Rgb([255; 3]),
                "near_first {near_first}"
            );
        }
    }

    #[test]
    fn values_are_interpolated_and_mapped() {
        assert_eq!(Colormap::Grey.color(2.0), Rgb([255; 3]));
        assert_eq!(Colormap::Grey.color(-1.0), Rgb([0; 3]));
        assert_eq!(Colormap::Error { max: 2.0 }.color(0.0), Rgb([59, 76, 192]));
        assert_eq!(Colormap::Error { max: 2.0 }.color(1.0), Rgb([221; 3]));
        assert_eq!(Colormap::Error { max: 2.0 }.color(9.0), Rgb([180, 4, 38]));
        let (positions, t) = triangle(0.0, 0.0);
        let mesh = Mesh::with_area_weighted_normals(positions, vec![t]);
        let image = render_scalar(
            &mesh,
            &[0.0, 1.0, 0.0],
            View {
                yaw: 0.0,
                pitch: 0.0,
            },
            100,
            100,
            Colormap::Grey,
        )
        .unwrap();
        // Pixel centre (50.5, 93.5) is at u ≈ 0.505 along the edge from vertex 0 to 1.
        let g = image.get_pixel(50, 93)[0];
        assert!((g as f32 - 0.505 * 255.0).abs() < 3.0, "{g}");
        assert!(matches!(
            render_scalar(
                &mesh,
                &[0.0],
                View {
                    yaw: 0.0,
                    pitch: 0.0
                },
                8,
                8,
                Colormap::Grey
            ),
            Err(RenderError::ValueCount {
                values: 1,
                vertices: 3
            })
        ));
    }

    #[test]
    fn panels_are_joined_with_a_gutter_and_saved_atomically() {
        let a = RgbImage::from_pixel(3, 2, Rgb([1, 2, 3]));
        let b = RgbImage::from_pixel(2, 4, Rgb([4, 5, 6]));
        let joined = side_by_side(&[a, b]);
        assert_eq!(joined.dimensions(), (3 + GUTTER + 2, 4));
        assert_eq!(*joined.get_pixel(0, 0), Rgb([1, 2, 3]));
        assert_eq!(*joined.get_pixel(3, 0), BACKGROUND);
        assert_eq!(*joined.get_pixel(0, 3), BACKGROUND);
        assert_eq!(*joined.get_pixel(3 + GUTTER, 3), Rgb([4, 5, 6]));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("panel.png");
        save_png_atomic(&path, &joined).unwrap();
        let back = image::open(&path).unwrap().to_rgb8();
        assert_eq!(back, joined);
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            1,
            "no temporary file left behind"
        );
        assert!(matches!(
            save_png_atomic(&dir.path().join("missing/dir/x.png"), &joined),
            Err(RenderError::Io { .. })
        ));
    }

    /// A grid of points on a square facing the camera, each a disc of its share of the area,
    /// covers the square's pixels without a gap; a nearer point in front of it wins its disc
    /// whatever the drawing order, and a farther one behind it shows nowhere.
    #[test]
    fn splats_cover_their_surface_and_the_nearest_point_wins() {
        let n = 40;
        let mut positions: Vec<[f32; 3]> = (0..n * n)
            .map(|i| {
                let (x, z) = ((i % n) as f32 + 0.5, (i / n) as f32 + 0.5);
                [x / n as f32, 0.0, z / n as f32]
            })
            .collect();
        let share = (1.0 / (n * n) as f32 / std::f32::consts::PI).sqrt();
        let mut radii = vec![1.5 * share; n * n];
        let front = View {
            yaw: 0.0,
            pitch: 0.0,
        };
        let square = render_splats(&positions, &radii, front, (100, 100), |_| Rgb([9, 9, 9]));
        let square = square.unwrap();
        // The points span 0.975 of the unit square around its centre: pixels 6..94.
        for y in 8..92 {
            for x in 8..92 {
                assert_eq!(*square.get_pixel(x, y), Rgb([9, 9, 9]), "gap at {x}, {y}");
            }
        }
        // One point in front of the centre (−y is toward the camera), one behind it.
        positions.push([0.5, -1.0, 0.5]);
        positions.push([0.5, 1.0, 0.5]);
        radii.extend([0.1, 0.1]);
        let near = positions.len() - 2;
        let image = render_splats(&positions, &radii, front, (100, 100), |i| match i {
            i if i == near => Rgb([255, 0, 0]),
            i if i == near + 1 => Rgb([0, 0, 255]),
            _ => Rgb([9, 9, 9]),
        })
        .unwrap();
        assert_eq!(*image.get_pixel(50, 50), Rgb([255, 0, 0]));
        assert!(image.pixels().all(|p| *p != Rgb([0, 0, 255])));
        assert!(matches!(
            render_splats(&positions, &radii[1..], front, (10, 10), |_| BACKGROUND),
            Err(RenderError::ValueCount { .. })
        ));
    }
}
