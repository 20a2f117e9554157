//! The projection against closed forms: a constant map, one bright texel (as its solid angle
//! at its centre, and against the basis integrated finely over its patch), a map equal to a
//! band-1 function, the direction convention; the two file formats round-tripped through
//! their encoders; and the refusals.
//!
//! The resolution bounds come from Bernstein's inequality: along any great circle (a
//! meridian) or latitude circle a band-`l` function is a trigonometric polynomial of degree
//! `≤ l`, so its first and second derivatives in `θ` or `φ` are at most `l·M` and `l²·M`,
//! with `M = max|y_lm| ≤ √((2l+1)/4π)` by the addition theorem.

use std::f64::consts::PI;
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use aprt_core::eval_basis;
use image::Rgb32FImage;
use image::codecs::hdr::HdrEncoder;
use image::codecs::openexr::OpenExrEncoder;

use super::*;

/// `max|y_lm|` over the sphere for band `l`.
fn sup_basis(l: usize) -> f64 {
    ((2 * l + 1) as f64 / (4.0 * PI)).sqrt()
}

/// The band of coefficient index `c = l² + l + m`.
fn band(c: usize) -> usize {
    (c as f64).sqrt().floor() as usize
}

/// The documented direction of texel `(x, y)`'s centre, computed here from the module doc.
fn texel_direction(x: usize, y: usize, width: usize, height: usize) -> [f64; 3] {
    let theta = PI * (y as f64 + 0.5) / height as f64;
    let phi = 2.0 * PI * (x as f64 + 0.5) / width as f64 - PI;
    [
        theta.sin() * phi.cos(),
        theta.cos(),
        theta.sin() * phi.sin(),
    ]
}

/// The exact solid angle of a texel of row `y`, from the cosines of its edges.
fn texel_solid_angle(y: usize, width: usize, height: usize) -> f64 {
    let top = PI * y as f64 / height as f64;
    let bottom = PI * (y + 1) as f64 / height as f64;
    2.0 * PI / width as f64 * (top.cos() - bottom.cos())
}

/// Bands 0..=2 of the core's convention written out as polynomials (no Condon–Shortley
/// phase, `y_{1,-1} ∝ y`, `y_{1,0} ∝ z`, `y_{1,1} ∝ x`), independent of `eval_basis`.
fn explicit_basis([x, y, z]: [f64; 3]) -> [f64; 9] {
    let k0 = 0.5 / PI.sqrt();
    let k1 = (3.0 / (4.0 * PI)).sqrt();
    let k2 = 0.5 * (15.0 / PI).sqrt();
    let k20 = 0.25 * (5.0 / PI).sqrt();
    [
        k0,
        k1 * y,
        k1 * z,
        k1 * x,
        k2 * x * y,
        k2 * y * z,
        k20 * (3.0 * z * z - 1.0),
        k2 * x * z,
        0.5 * k2 * (x * x - y * y),
    ]
}

/// How far the centre rule can be from the exact projection of a smooth map, for one
/// coefficient: the map times the basis function has degree `degree` and magnitude at most
/// `sup`, and the map is `height` rows high (and wider than `degree` texels, so the equally
/// spaced columns integrate it exactly in `φ`). Per row of half-height `h`, the first-order
/// term integrates to at most `2h³/3 · |G'|` and the second-order one to `2h³/3 · |G''|/2`,
/// where `G(θ) = ∫ f y dφ` has `|G'| ≤ 2π·degree·sup`, `|G''| ≤ 2π·degree²·sup`; summed over
/// the rows with `h = π/2H` that is `π⁴ sup (D + D²/2) / 6H²`.
fn centre_rule_bound(sup: f64, degree: usize, height: usize) -> f64 {
    let d = degree as f64;
    PI.powi(4) * sup * (d + d * d / 2.0) / (6.0 * (height * height) as f64)
}

/// How far `Ω y(centre)` can be from `∫ y dω` over one texel of polar half-height `a` and
/// azimuthal half-width `b` around polar angle `theta`, for band `l` (see the module doc).
fn texel_bound(l: usize, a: f64, b: f64, theta: f64) -> f64 {
    let l = l as f64;
    let first = l * 4.0 / 3.0 * a.powi(3) * b * theta.cos().abs();
    let second =
        0.5 * l * l * (4.0 / 3.0 * a.powi(3) * b + 2.0 * a * a * b * b + 4.0 / 3.0 * a * b.powi(3));
    sup_basis(l as usize) * (first + second)
}

/// `∫ y_k dω` over texel `(x, y)`, by the centre rule on an `n × n` grid of sub-patches, each
/// with its exact solid angle.
fn patch_integral(
    x: usize,
    y: usize,
    width: usize,
    height: usize,
    order: usize,
    n: usize,
) -> Vec<f64> {
    let mut total = vec![0.0; order * order];
    let mut basis = vec![0.0f32; order * order];
    for i in 0..n {
        let (t0, t1) = ((y * n + i) as f64, (y * n + i + 1) as f64);
        let (top, bottom) = (PI * t0 / (height * n) as f64, PI * t1 / (height * n) as f64);
        let omega = 2.0 * PI / (width * n) as f64 * (top.cos() - bottom.cos());
        for j in 0..n {
            let d = texel_direction(x * n + j, y * n + i, width * n, height * n);
            eval_basis(order, d.map(|v| v as f32), &mut basis).unwrap();
            for (t, &b) in total.iter_mut().zip(&basis) {
                *t += omega * f64::from(b);
            }
        }
    }
    total
}

fn one_bright_texel(
    width: usize,
    height: usize,
    x: usize,
    y: usize,
    value: [f32; 3],
) -> Vec<[f32; 3]> {
    let mut pixels = vec![[0.0f32; 3]; width * height];
    pixels[y * width + x] = value;
    pixels
}

#[test]
fn a_constant_map_projects_to_band_zero_alone() {
    let radiance = [1.5f32, 0.25, 3.0];
    for (width, height) in [(64, 32), (45, 23), (13, 7)] {
        let sh = project_equirect(&vec![radiance; width * height], width, height, 6).unwrap();
        assert_eq!(sh.len(), 36);
        for k in 0..3 {
            let expected = f64::from(radiance[k]) * (4.0 * PI).sqrt();
            let rel = (f64::from(sh[0][k]) - expected).abs() / expected;
            assert!(
                rel < 1e-6,
                "{width}x{height} channel {k}: c0 {} vs {expected}",
                sh[0][k]
            );
            for (c, coeff) in sh.iter().enumerate().skip(1) {
                let l = band(c);
                let sup = f64::from(radiance[k]) * sup_basis(l);
                let bound = centre_rule_bound(sup, l, height) + 4.0 * PI * sup * 2e-6;
                assert!(
                    f64::from(coeff[k]).abs() <= bound,
                    "{width}x{height} channel {k} coefficient {c}: {} > {bound}",
                    coeff[k]
                );
            }
        }
    }
}

#[test]
fn one_bright_texel_is_its_solid_angle_at_its_centre() {
    let value = [2.0f32, 0.5, 7.0];
    let cases = [
        (64, 32, 37, 11),
        (64, 32, 5, 0),
        (45, 23, 44, 22),
        (45, 23, 22, 11),
    ];
    for (width, height, x, y) in cases {
        let pixels = one_bright_texel(width, height, x, y, value);
        let sh = project_equirect(&pixels, width, height, 3).unwrap();
        let omega = texel_solid_angle(y, width, height);
        let basis = explicit_basis(texel_direction(x, y, width, height));
        for (c, coeff) in sh.iter().enumerate() {
            for k in 0..3 {
                let expected = f64::from(value[k]) * omega * basis[c];
                let tolerance = 2e-6 * f64::from(value[k]) * omega * sup_basis(band(c));
                assert!(
                    (f64::from(coeff[k]) - expected).abs() <= tolerance,
                    "texel ({x}, {y}) of {width}x{height}, coefficient {c} channel {k}: {} vs {expected}",
                    coeff[k]
                );
            }
        }
    }
}

#[test]
fn one_bright_texel_matches_the_basis_integrated_over_its_patch() {
    let n = 48;
    let cases = [
        (64, 32, 37, 11),
        (64, 32, 5, 0),
        (45, 23, 3, 21),
        (128, 64, 100, 31),
    ];
    for (width, height, x, y) in cases {
        let radiance = 3.0f32;
        let pixels = one_bright_texel(width, height, x, y, [radiance; 3]);
        let sh = project_equirect(&pixels, width, height, 6).unwrap();
        let exact = patch_integral(x, y, width, height, 6, n);
        let (a, b) = (PI / (2.0 * height as f64), PI / width as f64);
        let theta = PI * (y as f64 + 0.5) / height as f64;
        let omega = texel_solid_angle(y, width, height);
        for (c, (coeff, integral)) in sh.iter().zip(&exact).enumerate() {
            let l = band(c);
            // The fine grid's own error is the same bound over n² sub-patches a n-th the size.
            let bound = texel_bound(l, a, b, theta) + texel_bound(l, a, b, 0.0) / (n * n) as f64;
            let tolerance = f64::from(radiance) * (bound + 4e-6 * omega * sup_basis(l));
            let error = (f64::from(coeff[0]) - f64::from(radiance) * integral).abs();
            assert!(
                error <= tolerance,
                "texel ({x}, {y}) of {width}x{height}, coefficient {c}: off by {error} > {tolerance}"
            );
        }
    }
}

#[test]
fn the_centre_column_faces_plus_x_and_three_quarters_across_plus_z() {
    // Band 1 of one texel is L Ω k (y, z, x) of its direction: read the direction back.
    let facing = |width: usize, height: usize, x: usize, y: usize| {
        let sh = project_equirect(
            &one_bright_texel(width, height, x, y, [1.0; 3]),
            width,
            height,
            2,
        )
        .unwrap();
        let [cy, cz, cx] = [sh[1][0], sh[2][0], sh[3][0]];
        let len = (cx * cx + cy * cy + cz * cz).sqrt();
        [cx / len, cy / len, cz / len]
    };
    let close = |a: [f32; 3], b: [f32; 3]| a.iter().zip(&b).all(|(p, q)| (p - q).abs() < 1e-6);
    assert!(
        close(facing(9, 5, 4, 2), [1.0, 0.0, 0.0]),
        "centre: {:?}",
        facing(9, 5, 4, 2)
    );
    assert!(
        close(facing(6, 5, 4, 2), [0.0, 0.0, 1.0]),
        "3/4: {:?}",
        facing(6, 5, 4, 2)
    );
    assert!(
        close(facing(6, 5, 1, 2), [0.0, 0.0, -1.0]),
        "1/4: {:?}",
        facing(6, 5, 1, 2)
    );
    let top = facing(9, 5, 4, 0);
    assert!(top[1] > 0.8 && top[0] > 0.0, "row 0 leans to +Y: {top:?}");
    let bottom = facing(9, 5, 4, 4);
    assert!(bottom[1] < -0.8, "the last row leans to -Y: {bottom:?}");
}

#[test]
fn a_band_one_map_projects_to_its_coefficients() {
    // L(ω) = a + b ω_y + c ω_x per channel, non-negative since a > |(b, c)|.
    let (a, b, c) = (2.0f64, 0.7, -0.5);
    let scale = [1.0f64, 0.5, 2.0];
    let k1 = (3.0 / (4.0 * PI)).sqrt();
    for (width, height) in [(64, 32), (33, 17)] {
        let pixels: Vec<[f32; 3]> = (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .map(|(x, y)| {
                let [dx, dy, _] = texel_direction(x, y, width, height);
                scale.map(|s| (s * (a + b * dy + c * dx)) as f32)
            })
            .collect();
        let sh = project_equirect(&pixels, width, height, 6).unwrap();
        for (k, s) in scale.iter().enumerate() {
            let mut expected = [0.0f64; 36];
            expected[0] = s * a * (4.0 * PI).sqrt();
            expected[1] = s * b / k1;
            expected[3] = s * c / k1;
            let sup_map = s * (a + b.hypot(c));
            for (i, coeff) in sh.iter().enumerate() {
                let l = band(i);
                let sup = sup_map * sup_basis(l);
                let bound = centre_rule_bound(sup, l + 1, height) + 4.0 * PI * sup * 2e-6;
                let error = (f64::from(coeff[k]) - expected[i]).abs();
                assert!(
                    error <= bound,
                    "{width}x{height} channel {k} coefficient {i}: {} vs {}, off by {error} > {bound}",
                    coeff[k],
                    expected[i]
                );
            }
        }
    }
}

/// A map no flip or transpose leaves unchanged, in multiples of 1/256 below 1 plus one texel
/// of 4, 2, 0.5: values RGBE stores exactly (a shared exponent, 8-bit truncated mantissas).
fn rgbe_exact_map(width: usize, height: usize) -> Vec<[f32; 3]> {
    let mut pixels: Vec<[f32; 3]> = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| {
            let r = (7 * x + 3 * y) % 256;
            let g = (x + 5 * y) % 200;
            let b = (x * y) % 97;
            [r, g, b].map(|v| v as f32 / 256.0)
        })
        .collect();
    pixels[width + 3] = [4.0, 2.0, 0.5];
    pixels
}

fn image_of(pixels: &[[f32; 3]], width: usize, height: usize) -> Rgb32FImage {
    let flat = pixels.iter().flatten().copied().collect();
    Rgb32FImage::from_raw(width as u32, height as u32, flat).unwrap()
}

fn write_hdr(path: &Path, pixels: &[[f32; 3]], width: usize, height: usize) {
    let file = BufWriter::new(File::create(path).unwrap());
    image_of(pixels, width, height)
        .write_with_encoder(HdrEncoder::new(file))
        .unwrap();
}

fn write_exr(path: &Path, pixels: &[[f32; 3]], width: usize, height: usize) {
    let file = BufWriter::new(File::create(path).unwrap());
    image_of(pixels, width, height)
        .write_with_encoder(OpenExrEncoder::new(file))
        .unwrap();
}

#[test]
fn an_hdr_file_round_trips_through_read_environment() {
    let dir = tempfile::tempdir().unwrap();
    let (width, height) = (16, 8);
    let pixels = rgbe_exact_map(width, height);
    for name in ["sky.hdr", "SKY.HDR"] {
        let path = dir.path().join(name);
        write_hdr(&path, &pixels, width, height);
        let image = read_equirect(&path).unwrap();
        assert_eq!((image.width, image.height), (width, height));
        assert_eq!(
            image.pixels, pixels,
            "{name}: RGBE stores these values exactly"
        );
        let from_file = read_environment(&path, 4).unwrap();
        assert_eq!(
            from_file,
            project_equirect(&pixels, width, height, 4).unwrap()
        );
    }
}

#[test]
fn an_exr_file_round_trips_through_read_environment() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sky.exr");
    let (width, height) = (20, 9);
    let pixels: Vec<[f32; 3]> = (0..width * height)
        .map(|i| {
            [
                0.1 * i as f32,
                1.0 / (1.0 + i as f32),
                (i % 7) as f32 * 13.25,
            ]
        })
        .collect();
    write_exr(&path, &pixels, width, height);
    let image = read_equirect(&path).unwrap();
    assert_eq!((image.width, image.height), (width, height));
    assert_eq!(image.pixels, pixels, "OpenEXR stores f32 exactly");
    let from_file = read_environment(&path, 6).unwrap();
    assert_eq!(
        from_file,
        project_equirect(&pixels, width, height, 6).unwrap()
    );
}

#[test]
fn a_truncated_hdr_is_a_decode_error_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cut.hdr");
    write_hdr(&path, &rgbe_exact_map(16, 8), 16, 8);
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let err = read_environment(&path, 3).unwrap_err();
    assert!(
        matches!(&err, EnvMapError::Decode { path: p, format: "Radiance HDR", .. } if p == &path),
        "{err}"
    );
    assert!(err.to_string().contains("cut.hdr"), "{err}");
}

/// An OpenEXR header whose display window is 700000001 × 700000001 texels is refused for its
/// size, by the file's budget and by a small one given with the bytes: its byte count (× 40)
/// overflowed a u64 (found by the `env_map` fuzz target).
#[test]
fn a_map_too_large_to_count_in_bytes_is_refused_for_its_size() {
    let mut bytes = Vec::new();
    image_of(&rgbe_exact_map(8, 4), 8, 4)
        .write_with_encoder(OpenExrEncoder::new(std::io::Cursor::new(&mut bytes)))
        .unwrap();
    let name = b"displayWindow\0box2i\0";
    let at = bytes.windows(name.len()).position(|w| w == name).unwrap() + name.len() + 4;
    let side: i32 = 700_000_000;
    bytes[at..at + 16]
        .copy_from_slice(&[[0; 4], [0; 4], side.to_le_bytes(), side.to_le_bytes()].concat());
    for limit in [MAX_BYTES, 1 << 20] {
        let err = decode_equirect(Path::new("huge.exr"), &bytes, limit).unwrap_err();
        let side = side as u32 + 1;
        assert!(
            matches!(err, EnvMapError::TooLarge { width, height, limit: l, .. }
                if (width, height, l) == (side, side, limit)),
            "{err:?}"
        );
        assert!(
            err.to_string()
                .starts_with("huge.exr: a 700000001x700000001"),
            "{err}"
        );
    }
}

#[test]
fn unknown_extensions_and_missing_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["sky.png", "sky", "sky.hdr.txt"] {
        let path = dir.path().join(name);
        std::fs::write(&path, b"#?RADIANCE\n").unwrap();
        let err = read_environment(&path, 3).unwrap_err();
        assert!(
            matches!(&err, EnvMapError::UnknownExtension { path: p } if p == &path),
            "{err}"
        );
        assert!(err.to_string().contains(name), "{err}");
    }
    let missing = dir.path().join("missing.exr");
    let err = read_environment(&missing, 3).unwrap_err();
    assert!(
        matches!(&err, EnvMapError::Unreadable(e) if e.path == missing),
        "{err}"
    );
}

#[test]
fn bad_texels_are_named_by_position() {
    let (width, height) = (8, 4);
    for bad in [f32::NAN, f32::INFINITY, -0.25] {
        let mut pixels = vec![[1.0f32; 3]; width * height];
        pixels[2 * width + 3][1] = bad;
        pixels[3 * width + 5][0] = bad; // later in row-major order: not the one reported
        let err = project_equirect(&pixels, width, height, 3).unwrap_err();
        assert!(
            matches!(
                err,
                EnvMapError::BadTexel {
                    file: None,
                    x: 3,
                    y: 2,
                    ..
                }
            ),
            "{bad}: {err}"
        );
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nan.exr");
    let mut pixels = vec![[0.5f32; 3]; width * height];
    pixels[width + 6] = [0.5, f32::NAN, 0.5];
    write_exr(&path, &pixels, width, height);
    let err = read_environment(&path, 3).unwrap_err();
    assert!(
        matches!(&err, EnvMapError::BadTexel { file: Some(p), x: 6, y: 1, .. } if p == &path),
        "{err}"
    );
    assert!(
        err.to_string().contains("nan.exr") && err.to_string().contains("(6, 1)"),
        "{err}"
    );
}

#[test]
fn empty_mismatched_and_bad_orders_are_refused() {
    assert!(matches!(
        project_equirect(&[], 0, 4, 3),
        Err(EnvMapError::ZeroSize {
            width: 0,
            height: 4,
            ..
        })
    ));
    assert!(matches!(
        project_equirect(&[[1.0; 3]; 5], 2, 3, 3),
        Err(EnvMapError::SizeMismatch {
            width: 2,
            height: 3,
            len: 5
        })
    ));
    for order in [0, 7] {
        assert!(matches!(
            project_equirect(&[[1.0; 3]; 6], 3, 2, order),
            Err(EnvMapError::BadOrder { order: o }) if o == order
        ));
        // The order is checked before the file is opened.
        assert!(matches!(
            read_environment(Path::new("/nonexistent/sky.hdr"), order),
            Err(EnvMapError::BadOrder { .. })
        ));
    }
}
