//! Environment maps: an equirectangular `.hdr` (Radiance RGBE) or `.exr` (OpenEXR) image
//! projected to SH radiance in the core's basis ([`aprt_core::eval_basis`]), the distant
//! lighting a scene hands to `IrradianceRig::vectors_from_lights` and `aprt light env` prints.
//!
//! # Which direction a texel faces
//! A map `W` texels wide and `H` high covers the sphere once, world axes with +Y up. Texel
//! `(x, y)` (column `x` from the left, row `y` from the top) spans the polar angle
//! `θ ∈ [πy/H, π(y+1)/H]`, measured from +Y, and the azimuth `φ ∈ [2πx/W − π, 2π(x+1)/W − π]`;
//! its direction is `(sin θ cos φ, cos θ, sin θ sin φ)` at the centre
//! `θ = π(y+½)/H, φ = 2π(x+½)/W − π`. So row 0 touches +Y and the last row −Y; the left and
//! right edges face −X, the centre column +X, one quarter across −Z and three quarters across
//! +Z. Seen from inside the sphere, up +Y, the image is not mirrored: right in the image is a
//! turn to the right.
//!
//! This is the convention of three.js (`equirectUv`: `u = atan2(z, x)/2π + ½`,
//! `v = asin(y)/π + ½` with `v` up) and of Blender's environment texture (Cycles'
//! `direction_to_equirectangular`: `u = ½ − atan2(y, x)/2π` with +Z up, the same directions
//! once its glTF exporter turns Blender's `(x, y, z)` into Y-up `(x, z, −y)`), so a map shown
//! as the background of either lights the character from where it is seen there.
//!
//! # The projection
//! The map is piecewise constant: texel `t` has radiance `L_t` over its patch of the sphere.
//! Each patch counts as its solid angle `Ω_t = (2π/W)(cos θ_top − cos θ_bottom)` at its centre
//! direction `ω_t`, so `c_k = Σ_t L_t Ω_t y_k(ω_t)`, summed in f64. The solid angles are exact
//! (not `sin θ Δθ Δφ`), so they sum to 4π and a constant map's `c_0` is exact at any size.
//!
//! The centre is enough, with no supersampling, because the basis is smooth at the scale of a
//! texel. Within one texel a band-`l` function changes by at most `l · Δ · max|y|`
//! (Bernstein's inequality along great circles and latitude circles; `Δ` the texel's angular
//! size), and the first-order part cancels across the texel, so each texel's share is off by
//! `O((lΔ)²) Ω_t max|y|` (`O(lΔ)` in the two rows touching the poles, whose patches are thin
//! wedges). At order 6 (`l ≤ 5`) a 512 × 256 map has `lΔ < 0.07`, and the bound the tests use
//! puts each texel with `θ` between 45° and 135° within 0.1 % of `Ω_t max|y|` (the relative
//! error grows as `1/sin θ` towards the poles, where the texels are small). The tests check one
//! bright texel both against `L Ω y(ω_t)` and against the basis integrated finely over its
//! patch.

use std::f64::consts::PI;
use std::io::Cursor;
use std::path::{Path, PathBuf};

use aprt_core::{MAX_COEFFS, MAX_ORDER, eval_basis};
use image::{ImageFormat, ImageReader};
use rayon::prelude::*;

use crate::bake::budget;
use crate::input::{InputError, InputKind, read_input};
use crate::limits::MAX_BYTES;

/// Bytes a decoded texel holds at the peak: the decoder's RGBA f32, its RGB f32 conversion and
/// the pixels kept, 16 + 12 + 12.
const ENV_TEXEL_BYTES: u64 = 40;

/// Why an environment map could not be read or projected.
#[derive(Debug, thiserror::Error)]
pub enum EnvMapError {
    /// The file cannot be read (the error names it and why).
    #[error(transparent)]
    Unreadable(#[from] InputError),
    /// The name does not end in `.hdr` or `.exr`.
    #[error(
        "{}: unknown extension: an environment map is an equirectangular .hdr (Radiance RGBE) or .exr (OpenEXR)",
        path.display()
    )]
    UnknownExtension {
        /// The file.
        path: PathBuf,
    },
    /// The decoder refused the file (truncated, corrupt, or a variant it does not read).
    #[error("{}: not a readable {format} image", path.display())]
    Decode {
        /// The file.
        path: PathBuf,
        /// `Radiance HDR` or `OpenEXR`.
        format: &'static str,
        /// What the decoder said.
        source: image::ImageError,
    },
    /// The header claims more texels than one run may decode.
    #[error(
        "{}: a {width}x{height} environment map needs {} to decode ({width} × {height} texels, {ENV_TEXEL_BYTES} bytes each); one run holds at most {}: give a smaller map",
        path.display(),
        budget::bytes(decode_bytes(*width, *height)),
        budget::bytes(*limit)
    )]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its width, from the header.
        width: u32,
        /// Its height, from the header.
        height: u32,
        /// The bytes the decode may hold ([`MAX_BYTES`] for a file).
        limit: u64,
    },
    /// The image has no texels.
    #[error("{}: the image is {width}x{height}, with no texels", origin(file))]
    ZeroSize {
        /// The file, when the image came from one.
        file: Option<PathBuf>,
        /// Its width.
        width: usize,
        /// Its height.
        height: usize,
    },
    /// An in-memory image whose texel count is not `width × height`.
    #[error("{len} texels for a {width}x{height} image")]
    SizeMismatch {
        /// The width given.
        width: usize,
        /// The height given.
        height: usize,
        /// The texels given.
        len: usize,
    },
    /// A texel with NaN, infinite or negative radiance, which has no lighting meaning.
    #[error(
        "{}: texel ({x}, {y}) is {value:?}: radiance must be finite and non-negative",
        origin(file)
    )]
    BadTexel {
        /// The file, when the image came from one.
        file: Option<PathBuf>,
        /// Its column, from 0 at the left.
        x: usize,
        /// Its row, from 0 at the top.
        y: usize,
        /// Its RGB.
        value: [f32; 3],
    },
    /// A Radiance `EXPOSURE=` header that is not a positive number, so radiance cannot be
    /// recovered from the stored values.
    #[error(
        "{}: EXPOSURE is {exposure}: a Radiance file's exposure must be a positive number (radiance is the stored value divided by it)",
        path.display()
    )]
    BadExposure {
        /// The file.
        path: PathBuf,
        /// The product of its `EXPOSURE=` lines.
        exposure: f32,
    },
    /// A coefficient of the projection is beyond f32, the precision lighting is computed in.
    #[error(
        "{}: SH coefficient {index} of the projection is {value:e}, beyond f32 (up to {max:e}); the brightest texel ({x}, {y}) is {texel:?}: scale the map down",
        origin(file),
        max = f32::MAX
    )]
    Overflow {
        /// The file, when the image came from one.
        file: Option<PathBuf>,
        /// The coefficient, from 0.
        index: usize,
        /// Its value in f64.
        value: f64,
        /// The brightest texel's column.
        x: usize,
        /// Its row.
        y: usize,
        /// Its RGB.
        texel: [f32; 3],
    },
    /// The SH order is 0 or above the core's [`MAX_ORDER`].
    #[error("SH order {order} is outside 1..={MAX_ORDER}")]
    BadOrder {
        /// The order asked for.
        order: usize,
    },
}

/// How an error names its image: the file, or that it was handed over in memory.
fn origin(file: &Option<PathBuf>) -> String {
    match file {
        Some(path) => path.display().to_string(),
        None => "environment map".to_owned(),
    }
}

impl EnvMapError {
    /// The same error naming `path`, for problems [`project_equirect`] finds in a file's image.
    fn in_file(mut self, path: &Path) -> Self {
        if let Self::ZeroSize { file, .. }
        | Self::BadTexel { file, .. }
        | Self::Overflow { file, .. } = &mut self
        {
            *file = Some(path.to_path_buf());
        }
        self
    }
}

/// A decoded equirectangular map and the file it came from.
#[derive(Clone, Debug)]
pub struct EnvironmentImage {
    /// The file.
    pub path: PathBuf,
    /// Texels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Linear RGB radiance, row-major, row 0 at the top (+Y).
    pub pixels: Vec<[f32; 3]>,
}

impl EnvironmentImage {
    /// Its SH radiance of `order`, as [`project_equirect`]; errors name the file.
    pub fn project(&self, order: usize) -> Result<Vec<[f32; 3]>, EnvMapError> {
        project_equirect(&self.pixels, self.width, self.height, order)
            .map_err(|e| e.in_file(&self.path))
    }
}

/// Reads an equirectangular .hdr or .exr (by extension, case-insensitive) and projects it to SH
/// radiance of `order` (1..=6): order² RGB coefficients, in aprt-core's real orthonormal basis
/// (`aprt_core::eval_basis`, see core-nostd/src/sh.rs), world axes with +Y up.
///
/// The order is checked before the file is read, so a bad flag is not hidden behind a decode.
pub fn read_environment(path: &Path, order: usize) -> Result<Vec<[f32; 3]>, EnvMapError> {
    check_order(order)?;
    read_equirect(path)?.project(order)
}

/// Decodes an equirectangular .hdr or .exr (by extension, case-insensitive) to linear RGB; an
/// alpha channel is dropped. Texels are checked when the image is projected.
pub fn read_equirect(path: &Path) -> Result<EnvironmentImage, EnvMapError> {
    // The extension is checked before the file is read, so a wrong name is said as such.
    format_of(path)?;
    let bytes = read_input(path, InputKind::EnvironmentMap)?;
    decode_equirect(path, &bytes, MAX_BYTES)
}

/// Decodes the bytes of an equirectangular .hdr or .exr to linear RGB, as [`read_equirect`]
/// does with a file's: `path` picks the format by its extension and names the file in errors;
/// a header claiming more than `max_bytes` to decode is refused before a texel is decoded, and
/// the decoder allocates no more than that.
pub fn decode_equirect(
    path: &Path,
    bytes: &[u8],
    max_bytes: u64,
) -> Result<EnvironmentImage, EnvMapError> {
    let (format, name) = format_of(path)?;
    let exposure = match format {
        ImageFormat::Hdr => hdr_exposure(path, bytes)?,
        _ => 1.0,
    };
    let decode_error = |source| EnvMapError::Decode {
        path: path.to_path_buf(),
        format: name,
        source,
    };
    // The size is read from the header and checked before a texel is decoded.
    let (width, height) = ImageReader::with_format(Cursor::new(bytes), format)
        .into_dimensions()
        .map_err(decode_error)?;
    if decode_bytes(width, height) > max_bytes {
        return Err(EnvMapError::TooLarge {
            path: path.to_path_buf(),
            width,
            height,
            limit: max_bytes,
        });
    }
    let mut reader = ImageReader::with_format(Cursor::new(bytes), format);
    // The decoder's own default (512 MiB) would refuse maps the check above allows, without
    // their size.
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(max_bytes);
    reader.limits(limits);
    let decoded = reader.decode().map_err(decode_error)?.into_rgb32f();
    Ok(EnvironmentImage {
        path: path.to_path_buf(),
        width: decoded.width() as usize,
        height: decoded.height() as usize,
        pixels: decoded
            .pixels()
            .map(|p| p.0.map(|v| v / exposure))
            .collect(),
    })
}

/// Bytes a `width × height` map holds while it is decoded, saturating: the header's sizes are
/// u32, and two above about 6.8·10⁸ give more than a u64 holds (an OpenEXR display window of
/// 867188627 × 690896807 the `env_map` fuzz target wrote), which used to wrap around.
fn decode_bytes(width: u32, height: u32) -> u64 {
    (u64::from(width) * u64::from(height)).saturating_mul(ENV_TEXEL_BYTES)
}

/// The image format `path`'s extension names (case-insensitive), and its name for errors.
fn format_of(path: &Path) -> Result<(ImageFormat, &'static str), EnvMapError> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("hdr") => Ok((ImageFormat::Hdr, "Radiance HDR")),
        Some("exr") => Ok((ImageFormat::OpenExr, "OpenEXR")),
        _ => Err(EnvMapError::UnknownExtension {
            path: path.to_path_buf(),
        }),
    }
}

/// The exposure a Radiance file's texels were scaled by when written: the product of its
/// `EXPOSURE=` lines, 1 without one. Radiance is the stored value divided by it (Radiance's
/// file format documentation); the image crate reads the header but leaves the values as
/// stored, so the division is ours.
fn hdr_exposure(path: &Path, bytes: &[u8]) -> Result<f32, EnvMapError> {
    let decoder = image::codecs::hdr::HdrDecoder::new(Cursor::new(bytes)).map_err(|source| {
        EnvMapError::Decode {
            path: path.to_path_buf(),
            format: "Radiance HDR",
            source,
        }
    })?;
    match decoder.metadata().exposure {
        None => Ok(1.0),
        Some(e) if e.is_finite() && e > 0.0 => Ok(e),
        Some(exposure) => Err(EnvMapError::BadExposure {
            path: path.to_path_buf(),
            exposure,
        }),
    }
}

/// The projection itself on an in-memory RGB f32 image, width×height row-major, row 0 at the
/// top (+Y pole). Directions and weights are in the [module documentation](self).
///
/// Rows are summed in parallel, each in f64, and the row sums added in row order, so the
/// result does not depend on the thread count.
pub fn project_equirect(
    pixels: &[[f32; 3]],
    width: usize,
    height: usize,
    order: usize,
) -> Result<Vec<[f32; 3]>, EnvMapError> {
    check_order(order)?;
    check_texels(pixels, width, height)?;
    let n2 = order * order;
    // cos θ_top − cos θ_bottom = 2 sin θ_centre sin(π/2H): the same difference without the
    // cancellation of subtracting two nearby cosines.
    let half_row = (PI / (2.0 * height as f64)).sin();
    let column_weight = 2.0 * PI / width as f64;
    let azimuths: Vec<(f64, f64)> = (0..width)
        .map(|x| (2.0 * PI * (x as f64 + 0.5) / width as f64 - PI).sin_cos())
        .collect();
    let rows: Vec<[[f64; 3]; MAX_COEFFS]> = pixels
        .par_chunks(width)
        .enumerate()
        .map(|(y, row)| {
            let (sin_t, cos_t) = (PI * (y as f64 + 0.5) / height as f64).sin_cos();
            let solid_angle = column_weight * 2.0 * sin_t * half_row;
            let mut sum = row_sum(row, order, &azimuths, sin_t, cos_t);
            for c in &mut sum[..n2] {
                c.iter_mut().for_each(|v| *v *= solid_angle);
            }
            sum
        })
        .collect();
    let mut total = vec![[0.0f64; 3]; n2];
    for row in &rows {
        for (t, r) in total.iter_mut().zip(row) {
            (0..3).for_each(|k| t[k] += r[k]);
        }
    }
    let values = total.iter().flatten().enumerate();
    if let Some((i, &value)) = values.clone().find(|(_, v)| !(**v as f32).is_finite()) {
        // The first of equals (max_by keeps the last).
        let brightest = (0..pixels.len())
            .rev()
            .max_by(|&a, &b| max_channel(pixels[a]).total_cmp(&max_channel(pixels[b])))
            .unwrap_or(0);
        return Err(EnvMapError::Overflow {
            file: None,
            index: i / 3,
            value,
            x: brightest % width,
            y: brightest / width,
            texel: pixels[brightest],
        });
    }
    Ok(total.iter().map(|c| c.map(|v| v as f32)).collect())
}

fn max_channel(rgb: [f32; 3]) -> f32 {
    rgb.into_iter().fold(0.0, f32::max)
}

/// `Σ_x L(x) y(ω_x)` along one row of polar angle θ (every texel of a row has the same solid
/// angle, applied once by the caller).
fn row_sum(
    row: &[[f32; 3]],
    order: usize,
    azimuths: &[(f64, f64)],
    sin_t: f64,
    cos_t: f64,
) -> [[f64; 3]; MAX_COEFFS] {
    let n2 = order * order;
    let mut sum = [[0.0f64; 3]; MAX_COEFFS];
    let mut basis = [0.0f32; MAX_COEFFS];
    for (texel, &(sin_p, cos_p)) in row.iter().zip(azimuths) {
        if *texel == [0.0; 3] {
            continue;
        }
        let dir = [sin_t * cos_p, cos_t, sin_t * sin_p].map(|v| v as f32);
        eval_basis(order, dir, &mut basis[..n2])
            .expect("a texel direction is a unit vector and the order was checked");
        for (s, &y) in sum.iter_mut().zip(&basis[..n2]) {
            (0..3).for_each(|k| s[k] += f64::from(texel[k]) * f64::from(y));
        }
    }
    sum
}

fn check_order(order: usize) -> Result<(), EnvMapError> {
    if order == 0 || order > MAX_ORDER {
        return Err(EnvMapError::BadOrder { order });
    }
    Ok(())
}

/// The image has texels, as many as its size says, and each is finite and non-negative; the
/// first bad texel in row-major order is the one reported.
fn check_texels(pixels: &[[f32; 3]], width: usize, height: usize) -> Result<(), EnvMapError> {
    if width == 0 || height == 0 {
        return Err(EnvMapError::ZeroSize {
            file: None,
            width,
            height,
        });
    }
    if width.checked_mul(height) != Some(pixels.len()) {
        return Err(EnvMapError::SizeMismatch {
            width,
            height,
            len: pixels.len(),
        });
    }
    match pixels
        .iter()
        .position(|p| !p.iter().all(|v| v.is_finite() && *v >= 0.0))
    {
        Some(i) => Err(EnvMapError::BadTexel {
            file: None,
            x: i % width,
            y: i / width,
            value: pixels[i],
        }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests;
