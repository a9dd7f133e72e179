//! Image files: float RGB OpenEXR in and out, tonemapped sRGB PNG previews and false-colour error maps.
//!
//! # Conventions
//!
//! * **Reading** ([`read_image`]) accepts only regular files (a FIFO or device is refused
//!   before it is opened; see [`crate::files`]) and checks the declared size before any pixel
//!   memory is allocated: each side at most [`MAX_DIMENSION`], at most [`MAX_PIXELS`] pixels
//!   (16384 x 16384, the largest image the renderer makes).
//! * **Writing** is atomic ([`crate::files::write_atomic`]): every writer fills a temporary
//!   file next to the destination and renames it over the destination, so a failed or
//!   interrupted write leaves the old file (or none), never a truncated one.
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

use exr::prelude::{Encoding, Image as ExrImage, SpecificChannels, Vec2, WritableImage};

use crate::files::write_atomic;
use crate::image::Image;

mod false_color;
mod read;

pub use false_color::{false_color_rgb8, viridis, write_false_color, ErrorScale, INVALID_COLOR};
pub use read::{read_exr, read_hdr, read_image, read_pfm};

/// The largest width or height of an image read or written (guards against absurd headers).
pub const MAX_DIMENSION: usize = 1 << 16;

/// The most pixels an image read from a file may have: 16384 x 16384, the largest image the
/// renderer makes (`--width`, `--height` at most 16384). A larger declared size is refused
/// before any pixel memory is allocated ([`ImageError::TooLarge`]).
pub const MAX_PIXELS: usize = 16_384 * 16_384;

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
    /// The file declares more pixels than [`MAX_PIXELS`] or a side beyond [`MAX_DIMENSION`];
    /// refused before the pixels are read.
    #[error(
        "{path}: the image declares {width}x{height} pixels, more than allowed (at most \
         16384x16384 = {max_pixels} pixels, each side at most {max_side})",
        max_pixels = MAX_PIXELS,
        max_side = MAX_DIMENSION
    )]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Declared width in pixels.
        width: usize,
        /// Declared height in pixels.
        height: usize,
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

pub(crate) fn check_size(
    path: &Path,
    width: usize,
    height: usize,
    pixels: usize,
) -> Result<(), ImageError> {
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

/// [`ImageError::Io`] for `path`.
pub(crate) fn io_error(path: &Path) -> impl Fn(io::Error) -> ImageError + '_ {
    move |source| ImageError::Io {
        path: path.to_path_buf(),
        source,
    }
}

pub(crate) fn exr_error(path: &Path, error: exr::error::Error) -> ImageError {
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
/// The write is atomic ([`write_atomic`]): on failure `path` is left as it was.
///
/// # Errors
///
/// [`ImageError::InvalidSize`] for an empty or inconsistent image, [`ImageError::Io`] if the
/// file cannot be created or written, [`ImageError::Exr`] if the encoder fails.
pub fn write_exr(path: impl AsRef<Path>, image: &Image) -> Result<(), ImageError> {
    let path = path.as_ref();
    check_size(path, image.width, image.height, image.pixels.len())?;
    write_atomic(path, io_error(path), |writer| {
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
        .to_buffered(writer)
        .map_err(|e| exr_error(path, e))
    })
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

/// Writes 8-bit RGB as a PNG, atomically ([`write_atomic`]).
pub(crate) fn write_rgb8_png(
    path: &Path,
    bytes: &[u8],
    width: usize,
    height: usize,
) -> Result<(), ImageError> {
    use image::ImageEncoder as _;
    check_size(path, width, height, bytes.len() / 3)?;
    // check_size bounds both sides by MAX_DIMENSION, so they fit in u32.
    let (w, h) = (width as u32, height as u32);
    write_atomic(path, io_error(path), |writer| {
        image::codecs::png::PngEncoder::new(writer)
            .write_image(bytes, w, h, image::ExtendedColorType::Rgb8)
            .map_err(|e| match e {
                image::ImageError::IoError(source) => io_error(path)(source),
                other => ImageError::Png {
                    path: path.to_path_buf(),
                    reason: other.to_string(),
                },
            })
    })
}

/// Writes a tonemapped 8-bit sRGB PNG preview of `image` (see [`tonemap_srgb8`] and the module
/// docs for the exact mapping). `exposure` is in stops; 0 shows the radiance unchanged. The
/// write is atomic.
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

    /// An encoder failure leaves the previous file in place and no temporary file behind.
    #[test]
    fn failed_writes_keep_the_old_file() {
        let dir = temp_path("atomic");
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("kept.exr");
        write_exr(&path, &test_image()).unwrap();
        let before = std::fs::read(&path).unwrap();
        // An image whose pixel count does not match its size fails in the writer.
        let broken = Image {
            width: 5,
            height: 3,
            pixels: vec![[0.0; 3]; 2],
        };
        assert!(write_exr(&path, &broken).is_err());
        assert!(write_png(dir.join("kept.exr"), &test_image(), f32::NAN).is_err());
        assert_eq!(std::fs::read(&path).unwrap(), before);
        let names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, ["kept.exr"]);
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
}
