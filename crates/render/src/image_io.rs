//! Image files: float RGB OpenEXR in and out, tonemapped sRGB PNG previews and false-colour error maps.
//!
//! # Conventions
//!
//! * **EXR** files hold three `f32` channels `R`, `G`, `B` (no alpha), ZIP-compressed scan lines
//!   (lossless): [`write_exr`] then [`read_exr`] gives back bit-identical pixels, NaN and
//!   infinities included. [`read_exr`] reads the first RGB(A) layer of any EXR (half, float or
//!   uint samples are converted to `f32`; a missing channel reads as 0, alpha is ignored).
//! * **PNG previews** ([`write_png`], [`tonemap_srgb8`]) map linear radiance `x` to an 8-bit sRGB
//!   code value by
//!   `v = clamp(2^exposure · x, 0, 1)`, then the sRGB OETF
//!   `V = 12.92 v` for `v ≤ 0.0031308`, otherwise `V = 1.055 v^(1/2.4) − 0.055`, and finally
//!   `round(255 V)`. `exposure` is in stops (0 leaves the radiance unchanged, +1 doubles it).
//!   NaN becomes 0 (black) and +∞ becomes 1 (white), so a preview never fails on bad pixels.
//! * **Error maps** ([`write_false_color`], [`false_color_rgb8`]) colour one non-negative value per
//!   pixel (for `chainlight compare`: the per-pixel relative error of
//!   [`crate::metrics::relative_error_map`]) with the *viridis* colour map (dark purple = no error,
//!   blue, green, yellow = the top of the scale), on a linear or logarithmic [`ErrorScale`].
//!   Values beyond the scale are clamped to its ends; NaN or negative values are drawn magenta.

use std::io;
use std::path::{Path, PathBuf};

use exr::prelude::{
    read_first_rgba_layer_from_file, Encoding, Image as ExrImage, SpecificChannels, Vec2,
    WritableImage,
};

use crate::image::Image;

/// The largest width or height [`read_exr`] accepts (guards against absurd headers).
pub const MAX_DIMENSION: usize = 1 << 16;

/// Why an image file could not be read or written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ImageError {
    /// The operating system refused to open, create, read or write the file.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: io::Error,
    },
    /// The EXR file is malformed or uses a feature the `exr` crate does not support (or has no
    /// RGB layer).
    #[error("{path}: not a readable RGB OpenEXR file: {reason}")]
    Exr {
        /// The file.
        path: PathBuf,
        /// What the EXR decoder or encoder reported.
        reason: String,
    },
    /// The PFM file is malformed (bad header, size, scale or truncated data).
    #[error("{path}: not a readable PFM file: {reason}")]
    Pfm {
        /// The file.
        path: PathBuf,
        /// What was wrong.
        reason: String,
    },
    /// The Radiance HDR file is malformed.
    #[error("{path}: not a readable Radiance HDR file: {reason}")]
    Hdr {
        /// The file.
        path: PathBuf,
        /// What the decoder reported.
        reason: String,
    },
    /// The file's extension names no image format this crate reads.
    #[error("{path}: unsupported image format (expected .exr, .pfm or .hdr)")]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
    },
    /// The PNG encoder failed.
    #[error("{path}: cannot write PNG: {reason}")]
    Png {
        /// The file.
        path: PathBuf,
        /// What the PNG encoder reported.
        reason: String,
    },
    /// The image has a zero or too large dimension, or its pixel count does not match it.
    #[error(
        "{path}: invalid image size {width}x{height} with {pixels} pixels \
         (each side must be in 1..={max})",
        max = MAX_DIMENSION
    )]
    InvalidSize {
        /// The file.
        path: PathBuf,
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
        /// Number of pixels actually present.
        pixels: usize,
    },
    /// A parameter of the call is outside its allowed range (e.g. a non-finite exposure).
    #[error("{path}: {reason}")]
    InvalidParameter {
        /// The file that was to be written.
        path: PathBuf,
        /// Which parameter, its value and the allowed range.
        reason: String,
    },
}

fn check_size(path: &Path, width: usize, height: usize, pixels: usize) -> Result<(), ImageError> {
    let ok = (1..=MAX_DIMENSION).contains(&width)
        && (1..=MAX_DIMENSION).contains(&height)
        && width * height == pixels;
    if ok {
        Ok(())
    } else {
        Err(ImageError::InvalidSize {
            path: path.to_path_buf(),
            width,
            height,
            pixels,
        })
    }
}

fn exr_error(path: &Path, error: exr::error::Error) -> ImageError {
    match error {
        exr::error::Error::Io(source) => ImageError::Io {
            path: path.to_path_buf(),
            source,
        },
        other => ImageError::Exr {
            path: path.to_path_buf(),
            reason: other.to_string(),
        },
    }
}

/// Writes `image` to `path` as a float RGB OpenEXR file (three `f32` channels, lossless ZIP
/// compression). Reading it back with [`read_exr`] gives bit-identical pixels.
///
/// # Errors
///
/// [`ImageError::InvalidSize`] for an empty or inconsistent image, [`ImageError::Io`] if the
/// file cannot be created or written, [`ImageError::Exr`] if the encoder fails.
pub fn write_exr(path: impl AsRef<Path>, image: &Image) -> Result<(), ImageError> {
    let path = path.as_ref();
    check_size(path, image.width, image.height, image.pixels.len())?;
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let [r, g, b] = image.get(x, y);
        (r, g, b)
    });
    ExrImage::from_encoded_channels(
        (image.width, image.height),
        Encoding::SMALL_LOSSLESS,
        channels,
    )
    .write()
    .to_file(path)
    .map_err(|e| exr_error(path, e))
}

/// Reads an image by extension: `.exr` ([`read_exr`]), `.pfm` ([`read_pfm`]) or `.hdr`
/// ([`read_hdr`]).
///
/// # Errors
/// [`ImageError::UnsupportedFormat`] for other extensions, else as the reader.
pub fn read_image(path: impl AsRef<Path>) -> Result<Image, ImageError> {
    let path = path.as_ref();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("exr") => read_exr(path),
        Some("pfm") => read_pfm(path),
        Some("hdr") => read_hdr(path),
        _ => Err(ImageError::UnsupportedFormat {
            path: path.to_path_buf(),
        }),
    }
}

/// Reads a Radiance RGBE (`.hdr`) image, the usual format of downloadable environment maps,
/// through the `image` crate; the size is checked against [`MAX_DIMENSION`] before decoding.
///
/// # Errors
/// [`ImageError::Io`] if the file cannot be opened, [`ImageError::InvalidSize`] for absurd
/// sizes, [`ImageError::Exr`]-style decode errors as [`ImageError::Hdr`].
pub fn read_hdr(path: impl AsRef<Path>) -> Result<Image, ImageError> {
    let path = path.as_ref();
    let hdr_error = |reason: String| ImageError::Hdr {
        path: path.to_path_buf(),
        reason,
    };
    let open = || {
        image::ImageReader::open(path)
            .map_err(|source| ImageError::Io {
                path: path.to_path_buf(),
                source,
            })
            .map(|r| {
                let mut r = r;
                r.set_format(image::ImageFormat::Hdr);
                r
            })
    };
    let (w, h) = open()?
        .into_dimensions()
        .map_err(|e| hdr_error(e.to_string()))?;
    let (w, h) = (w as usize, h as usize);
    check_size(path, w, h, w.saturating_mul(h))?;
    let decoded = open()?.decode().map_err(|e| hdr_error(e.to_string()))?;
    let rgb = decoded.into_rgb32f();
    let mut image = Image::new(w, h);
    for (dst, px) in image.pixels.iter_mut().zip(rgb.pixels()) {
        *dst = px.0;
    }
    Ok(image)
}

/// Reads a colour Portable Float Map (`PF` header, width and height, scale whose sign gives
/// the byte order, rows bottom to top), the format of pbrt-style research renderers and of
/// corona-13's `pfmdiff`. Greyscale (`Pf`) maps are read as grey RGB.
///
/// # Errors
/// [`ImageError::Io`] if the file cannot be read, [`ImageError::Pfm`] if it is malformed.
pub fn read_pfm(path: impl AsRef<Path>) -> Result<Image, ImageError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| ImageError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let bad = |reason: &str| ImageError::Pfm {
        path: path.to_path_buf(),
        reason: reason.to_owned(),
    };
    // Three whitespace-separated header tokens after the magic, then one whitespace byte.
    let mut fields = Vec::new();
    let mut i = 0;
    while fields.len() < 4 {
        while i < bytes.len() && bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        let start = i;
        while i < bytes.len() && !bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        if start == i {
            return Err(bad("truncated header"));
        }
        fields.push(String::from_utf8_lossy(&bytes[start..i]).into_owned());
    }
    i += 1;
    let channels = match fields[0].as_str() {
        "PF" => 3,
        "Pf" => 1,
        _ => return Err(bad("missing PF/Pf magic")),
    };
    let width: usize = fields[1]
        .parse()
        .map_err(|_| bad("width is not a number"))?;
    let height: usize = fields[2]
        .parse()
        .map_err(|_| bad("height is not a number"))?;
    let scale: f32 = fields[3]
        .parse()
        .map_err(|_| bad("scale is not a number"))?;
    if width == 0 || height == 0 || width > MAX_DIMENSION || height > MAX_DIMENSION {
        return Err(bad("width and height must be in 1..=65536"));
    }
    if scale == 0.0 || !scale.is_finite() {
        return Err(bad("scale must be finite and nonzero"));
    }
    let need = width * height * channels * 4;
    let data = bytes
        .get(i..i + need)
        .ok_or_else(|| bad("pixel data is truncated"))?;
    let little = scale < 0.0;
    let mut image = Image::new(width, height);
    for (k, chunk) in data.chunks_exact(4).enumerate() {
        let raw = [chunk[0], chunk[1], chunk[2], chunk[3]];
        let v = if little {
            f32::from_le_bytes(raw)
        } else {
            f32::from_be_bytes(raw)
        };
        let (px, c) = (k / channels, k % channels);
        let (x, y) = (px % width, height - 1 - px / width);
        let p = &mut image.pixels[y * width + x];
        if channels == 1 {
            *p = [v; 3];
        } else {
            p[c] = v;
        }
    }
    Ok(image)
}

/// Reads the first RGB(A) layer of the OpenEXR file at `path` as `f32` linear RGB.
///
/// # Errors
///
/// [`ImageError::Io`] if the file cannot be opened or read, [`ImageError::Exr`] if it is not a
/// valid EXR or has no RGB layer, [`ImageError::InvalidSize`] if a side exceeds
/// [`MAX_DIMENSION`].
pub fn read_exr(path: impl AsRef<Path>) -> Result<Image, ImageError> {
    let path = path.as_ref();
    // The exr crate reports a missing file as a generic I/O error without the path: open it
    // first so the error names the file and the OS reason.
    std::fs::File::open(path).map_err(|source| ImageError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let decoded = read_first_rgba_layer_from_file(
        path,
        |resolution: Vec2<usize>, _channels: &_| {
            // Guard against absurd headers before allocating.
            let (w, h) = (resolution.width(), resolution.height());
            if w <= MAX_DIMENSION && h <= MAX_DIMENSION {
                Image::new(w, h)
            } else {
                Image {
                    width: w,
                    height: h,
                    pixels: Vec::new(),
                }
            }
        },
        |image: &mut Image, position: Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
            if !image.pixels.is_empty() {
                image.set(position.x(), position.y(), [r, g, b]);
            }
        },
    )
    .map_err(|e| exr_error(path, e))?;
    let image = decoded.layer_data.channel_data.pixels;
    check_size(path, image.width, image.height, image.pixels.len())?;
    Ok(image)
}

/// The sRGB opto-electronic transfer function (IEC 61966-2-1) of a linear value in `[0, 1]`.
#[must_use]
pub fn srgb_oetf(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// Tonemaps linear RGB to 8-bit sRGB: scale by `2^exposure`, clamp to `[0, 1]` (NaN → 0), apply
/// [`srgb_oetf`], round to 0..=255. Returns `width * height * 3` bytes, row-major, top row first.
#[must_use]
pub fn tonemap_srgb8(image: &Image, exposure: f32) -> Vec<u8> {
    let scale = exposure.exp2();
    let mut out = Vec::with_capacity(image.pixels.len() * 3);
    for p in &image.pixels {
        for &c in p {
            let v = scale * c;
            // `clamp` keeps NaN; map it to black explicitly.
            let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
            out.push((srgb_oetf(v) * 255.0).round() as u8);
        }
    }
    out
}

fn write_rgb8_png(
    path: &Path,
    bytes: &[u8],
    width: usize,
    height: usize,
) -> Result<(), ImageError> {
    check_size(path, width, height, bytes.len() / 3)?;
    // check_size bounds both sides by MAX_DIMENSION, so they fit in u32.
    let (w, h) = (width as u32, height as u32);
    image::save_buffer_with_format(
        path,
        bytes,
        w,
        h,
        image::ExtendedColorType::Rgb8,
        image::ImageFormat::Png,
    )
    .map_err(|e| match e {
        image::ImageError::IoError(source) => ImageError::Io {
            path: path.to_path_buf(),
            source,
        },
        other => ImageError::Png {
            path: path.to_path_buf(),
            reason: other.to_string(),
        },
    })
}

/// Writes a tonemapped 8-bit sRGB PNG preview of `image` (see [`tonemap_srgb8`] and the module
/// docs for the exact mapping). `exposure` is in stops; 0 shows the radiance unchanged.
///
/// # Errors
///
/// [`ImageError::InvalidParameter`] for a non-finite exposure, [`ImageError::InvalidSize`] for an
/// empty or inconsistent image, [`ImageError::Io`] / [`ImageError::Png`] if writing fails.
pub fn write_png(path: impl AsRef<Path>, image: &Image, exposure: f32) -> Result<(), ImageError> {
    let path = path.as_ref();
    if !exposure.is_finite() {
        return Err(ImageError::InvalidParameter {
            path: path.to_path_buf(),
            reason: format!("exposure must be a finite number of stops, got {exposure}"),
        });
    }
    check_size(path, image.width, image.height, image.pixels.len())?;
    write_rgb8_png(
        path,
        &tonemap_srgb8(image, exposure),
        image.width,
        image.height,
    )
}

/// How error values are mapped to the `[0, 1]` position on the colour map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ErrorScale {
    /// `t = value / max`, clamped to `[0, 1]`.
    Linear {
        /// The value drawn with the top colour (> 0).
        max: f32,
    },
    /// `t = log10(value / min) / log10(max / min)`, clamped to `[0, 1]`; values `≤ min` get the
    /// bottom colour.
    Log10 {
        /// The value drawn with the bottom colour (> 0).
        min: f32,
        /// The value drawn with the top colour (> `min`).
        max: f32,
    },
}

impl Default for ErrorScale {
    /// Logarithmic from 0.1% to 100% relative error.
    fn default() -> Self {
        Self::Log10 {
            min: 1e-3,
            max: 1.0,
        }
    }
}

impl ErrorScale {
    /// Checks the scale's bounds: finite, positive, and `min < max` for [`ErrorScale::Log10`].
    ///
    /// # Errors
    ///
    /// A message naming the bound, its value and the allowed range.
    pub fn validate(&self) -> Result<(), String> {
        let positive = |v: f32| v.is_finite() && v > 0.0;
        match *self {
            Self::Linear { max } if !positive(max) => Err(format!(
                "error-map maximum must be finite and > 0, got {max}"
            )),
            Self::Log10 { min, .. } if !positive(min) => Err(format!(
                "error-map minimum must be finite and > 0, got {min}"
            )),
            Self::Log10 { min, max } if !(max.is_finite() && max > min) => Err(format!(
                "error-map maximum must be finite and > the minimum {min}, got {max}"
            )),
            _ => Ok(()),
        }
    }

    /// The position of `value` on the colour map, in `[0, 1]`; `None` for NaN or negative values.
    #[must_use]
    pub fn position(&self, value: f32) -> Option<f32> {
        if value.is_nan() || value < 0.0 {
            return None;
        }
        let t = match *self {
            Self::Linear { max } => value / max,
            Self::Log10 { min, max } => {
                if value <= min {
                    0.0
                } else {
                    (value / min).log10() / (max / min).log10()
                }
            }
        };
        Some(if t.is_nan() { 1.0 } else { t.clamp(0.0, 1.0) })
    }
}

/// Eleven evenly spaced samples of matplotlib's viridis colour map (public domain, CC0),
/// interpolated linearly in between.
const VIRIDIS: [[u8; 3]; 11] = [
    [0x44, 0x01, 0x54],
    [0x48, 0x24, 0x75],
    [0x41, 0x44, 0x87],
    [0x35, 0x5f, 0x8d],
    [0x2a, 0x78, 0x8e],
    [0x21, 0x91, 0x8c],
    [0x22, 0xa8, 0x84],
    [0x44, 0xbf, 0x70],
    [0x7a, 0xd1, 0x51],
    [0xbd, 0xdf, 0x26],
    [0xfd, 0xe7, 0x25],
];

/// The colour drawn for NaN or negative error values.
pub const INVALID_COLOR: [u8; 3] = [255, 0, 255];

/// The viridis colour at position `t` in `[0, 1]` (clamped).
#[must_use]
pub fn viridis(t: f32) -> [u8; 3] {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = t * (VIRIDIS.len() - 1) as f32;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f32;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    [0, 1, 2].map(|c| (f32::from(a[c]) + f * (f32::from(b[c]) - f32::from(a[c]))).round() as u8)
}

/// Colours one value per pixel with [`viridis`] on `scale` ([`INVALID_COLOR`] for NaN or
/// negative values). Returns `values.len() * 3` bytes.
#[must_use]
pub fn false_color_rgb8(values: &[f32], scale: ErrorScale) -> Vec<u8> {
    values
        .iter()
        .flat_map(|&v| scale.position(v).map_or(INVALID_COLOR, viridis))
        .collect()
}

/// Writes a false-colour PNG of one value per pixel (row-major, top row first), coloured by
/// [`false_color_rgb8`]; see the module docs for the colour map.
///
/// # Errors
///
/// [`ImageError::InvalidParameter`] for an invalid `scale`, [`ImageError::InvalidSize`] if
/// `values.len() != width * height` or a side is 0, [`ImageError::Io`] / [`ImageError::Png`] if
/// writing fails.
pub fn write_false_color(
    path: impl AsRef<Path>,
    values: &[f32],
    width: usize,
    height: usize,
    scale: ErrorScale,
) -> Result<(), ImageError> {
    let path = path.as_ref();
    scale
        .validate()
        .map_err(|reason| ImageError::InvalidParameter {
            path: path.to_path_buf(),
            reason,
        })?;
    check_size(path, width, height, values.len())?;
    write_rgb8_png(path, &false_color_rgb8(values, scale), width, height)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_path(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("chainlight-image-io-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join(name)
    }

    fn test_image() -> Image {
        let mut image = Image::new(5, 3);
        for y in 0..3 {
            for x in 0..5 {
                let v = (x + 10 * y) as f32;
                image.set(x, y, [v * 0.1, 1.0 / (v + 1.0), -v * 1e-7 + 1e30]);
            }
        }
        image.set(1, 1, [f32::NAN, f32::INFINITY, f32::MIN_POSITIVE / 8.0]);
        image.set(4, 2, [0.1 + 0.2, f32::NEG_INFINITY, -0.0]);
        image
    }

    #[test]
    fn pfm_reads_both_byte_orders_and_rejects_garbage() {
        let dir = std::env::temp_dir().join(format!("chainlight-pfm-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // 2x1 image, bottom-to-top rows (one row here), little endian.
        let mut le = b"PF\n2 1\n-1.0\n".to_vec();
        let mut be = b"PF\n2 1\n1.0\n".to_vec();
        for v in [1.0f32, 2.0, 3.0, 4.0, 5.0, 6.0] {
            le.extend_from_slice(&v.to_le_bytes());
            be.extend_from_slice(&v.to_be_bytes());
        }
        for (name, bytes) in [("le.pfm", &le), ("be.pfm", &be)] {
            let p = dir.join(name);
            std::fs::write(&p, bytes).unwrap();
            let img = read_image(&p).unwrap();
            assert_eq!(img.pixels, vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
        }
        let bad = dir.join("bad.pfm");
        std::fs::write(&bad, &le[..le.len() - 3]).unwrap();
        assert!(matches!(read_pfm(&bad), Err(ImageError::Pfm { .. })));
        std::fs::write(&bad, b"P6\n1 1\n255\n").unwrap();
        assert!(matches!(read_pfm(&bad), Err(ImageError::Pfm { .. })));
        assert!(matches!(
            read_image(dir.join("x.png")),
            Err(ImageError::UnsupportedFormat { .. })
        ));
    }

    #[test]
    fn exr_round_trip_is_bit_exact() {
        let path = temp_path("round_trip.exr");
        let image = test_image();
        write_exr(&path, &image).unwrap();
        let back = read_exr(&path).unwrap();
        assert_eq!((back.width, back.height), (5, 3));
        for (a, b) in image.pixels.iter().zip(&back.pixels) {
            for c in 0..3 {
                assert_eq!(a[c].to_bits(), b[c].to_bits(), "{a:?} vs {b:?}");
            }
        }
    }

    #[test]
    fn exr_errors_name_the_file() {
        let missing = temp_path("does_not_exist.exr");
        let err = read_exr(&missing).unwrap_err();
        assert!(matches!(err, ImageError::Io { .. }), "{err:?}");
        assert!(err.to_string().contains("does_not_exist.exr"), "{err}");

        let garbage = temp_path("garbage.exr");
        std::fs::write(&garbage, b"this is not an exr file").unwrap();
        let err = read_exr(&garbage).unwrap_err();
        assert!(matches!(err, ImageError::Exr { .. }), "{err:?}");
        assert!(err.to_string().contains("garbage.exr"), "{err}");

        let empty = Image::new(0, 4);
        let err = write_exr(temp_path("empty.exr"), &empty).unwrap_err();
        assert!(
            matches!(err, ImageError::InvalidSize { width: 0, .. }),
            "{err:?}"
        );

        let bad_dir = temp_path("no_such_dir").join("x.exr");
        assert!(matches!(
            write_exr(&bad_dir, &test_image()),
            Err(ImageError::Io { .. })
        ));
    }

    #[test]
    fn tonemap_matches_the_documented_formula() {
        let image = Image::from_pixels(
            4,
            1,
            vec![
                [0.0, 1.0, 2.0],
                [0.5, 0.002, -1.0],
                [f32::NAN, f32::INFINITY, 0.25],
                [0.18; 3],
            ],
        )
        .unwrap();
        let bytes = tonemap_srgb8(&image, 0.0);
        // 0.5 -> 1.055 * 0.5^(1/2.4) - 0.055 = 0.7353569 -> 187.5 -> 188;
        // 0.002 -> 12.92 * 0.002 = 0.02584 -> 6.59 -> 7; 0.25 -> 0.5370987 -> 137;
        // 0.18 -> 0.4613561 -> 117.6 -> 118.
        assert_eq!(
            bytes,
            vec![0, 255, 255, 188, 7, 0, 0, 255, 137, 118, 118, 118]
        );
        // One stop up doubles the radiance: 0.25 -> 0.5.
        let up = tonemap_srgb8(&image, 1.0);
        assert_eq!(up[8], 188);
    }

    #[test]
    fn png_is_written_and_decodable() {
        let path = temp_path("preview.png");
        write_png(&path, &test_image(), 0.0).unwrap();
        let decoded = image::open(&path).unwrap().to_rgb8();
        assert_eq!(decoded.dimensions(), (5, 3));
        assert_eq!(decoded.as_raw(), &tonemap_srgb8(&test_image(), 0.0));
        let err = write_png(&path, &test_image(), f32::NAN).unwrap_err();
        assert!(err.to_string().contains("exposure"), "{err}");
    }

    #[test]
    fn false_color_scale_and_map() {
        assert_eq!(viridis(0.0), VIRIDIS[0]);
        assert_eq!(viridis(1.0), VIRIDIS[10]);
        assert_eq!(viridis(0.5), VIRIDIS[5]);
        assert_eq!(viridis(2.0), VIRIDIS[10]);
        let log = ErrorScale::Log10 {
            min: 1e-3,
            max: 1.0,
        };
        assert_eq!(log.position(0.0), Some(0.0));
        assert!((log.position(0.01).unwrap() - 1.0 / 3.0).abs() < 1e-6);
        assert_eq!(log.position(10.0), Some(1.0));
        assert_eq!(log.position(f32::INFINITY), Some(1.0));
        assert_eq!(log.position(f32::NAN), None);
        let lin = ErrorScale::Linear { max: 2.0 };
        assert_eq!(lin.position(1.0), Some(0.5));
        assert!(ErrorScale::Linear { max: 0.0 }.validate().is_err());
        assert!(ErrorScale::Log10 { min: 1.0, max: 1.0 }.validate().is_err());
        assert!(ErrorScale::default().validate().is_ok());

        let bytes = false_color_rgb8(&[0.0, 1.0, -1.0], lin);
        assert_eq!(bytes, [VIRIDIS[0], VIRIDIS[5], INVALID_COLOR].concat());

        let path = temp_path("errors.png");
        write_false_color(&path, &[0.0, 0.5, 1.0, 2.0], 2, 2, lin).unwrap();
        let decoded = image::open(&path).unwrap().to_rgb8();
        assert_eq!(decoded.dimensions(), (2, 2));
        let err = write_false_color(&path, &[0.0; 3], 2, 2, lin).unwrap_err();
        assert!(
            matches!(err, ImageError::InvalidSize { pixels: 3, .. }),
            "{err:?}"
        );
    }
}
