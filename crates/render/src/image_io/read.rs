//! Reading float images (OpenEXR, Portable Float Map, Radiance HDR) with bounded memory: only
//! regular files are read, and the declared size is checked against [`MAX_DIMENSION`] and
//! [`MAX_PIXELS`] before any pixel memory is allocated.

use std::io::{BufReader, Read, Seek};
use std::path::Path;

use exr::prelude::{ReadChannels as _, ReadLayers as _, Vec2};

use super::{check_size, exr_error, io_error, ImageError, MAX_DIMENSION, MAX_PIXELS};
use crate::files;
use crate::image::Image;

/// Bytes of a PFM file searched for its header (magic, width, height, scale).
const MAX_PFM_HEADER: u64 = 1024;

/// Refuses a declared size before anything of that size is allocated: each side must be in
/// `1..=`[`MAX_DIMENSION`] and the pixel count at most [`MAX_PIXELS`].
fn check_declared(path: &Path, width: usize, height: usize) -> Result<(), ImageError> {
    let sides_ok = (1..=MAX_DIMENSION).contains(&width) && (1..=MAX_DIMENSION).contains(&height);
    if sides_ok && width * height <= MAX_PIXELS {
        Ok(())
    } else {
        Err(ImageError::TooLarge {
            path: path.to_path_buf(),
            width,
            height,
        })
    }
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
/// through the `image` crate; the declared size is checked before decoding.
///
/// # Errors
/// [`ImageError::Io`] if the file cannot be opened or is not a regular file,
/// [`ImageError::TooLarge`] for a size beyond the limits, decode errors as
/// [`ImageError::Hdr`].
pub fn read_hdr(path: impl AsRef<Path>) -> Result<Image, ImageError> {
    let path = path.as_ref();
    let hdr_error = |reason: String| ImageError::Hdr {
        path: path.to_path_buf(),
        reason,
    };
    let file = files::open_regular(path).map_err(io_error(path))?;
    let reader = || image::ImageReader::with_format(BufReader::new(&file), image::ImageFormat::Hdr);
    let (w, h) = reader()
        .into_dimensions()
        .map_err(|e| hdr_error(e.to_string()))?;
    let (w, h) = (w as usize, h as usize);
    check_declared(path, w, h)?;
    (&file).rewind().map_err(io_error(path))?;
    let decoded = reader().decode().map_err(|e| hdr_error(e.to_string()))?;
    let rgb = decoded.into_rgb32f();
    let mut image = Image::new(w, h);
    for (dst, px) in image.pixels.iter_mut().zip(rgb.pixels()) {
        *dst = px.0;
    }
    Ok(image)
}

/// Reads a colour Portable Float Map (`PF` header, width and height, scale whose sign gives
/// the byte order, rows bottom to top), the format of pbrt-style research renderers and of
/// corona-13's `pfmdiff`. Greyscale (`Pf`) maps are read as grey RGB. The header's size is
/// checked against the limits and the file's length before the pixels are read.
///
/// # Errors
/// [`ImageError::Io`] if the file cannot be read or is not a regular file,
/// [`ImageError::TooLarge`] for a size beyond the limits, [`ImageError::Pfm`] if it is
/// malformed.
pub fn read_pfm(path: impl AsRef<Path>) -> Result<Image, ImageError> {
    let path = path.as_ref();
    let bad = |reason: &str| ImageError::Pfm {
        path: path.to_path_buf(),
        reason: reason.to_owned(),
    };
    let file = files::open_regular(path).map_err(io_error(path))?;
    let len = file.metadata().map_err(io_error(path))?.len();
    let mut reader = BufReader::new(file);
    let mut bytes = Vec::new();
    (&mut reader)
        .take(MAX_PFM_HEADER)
        .read_to_end(&mut bytes)
        .map_err(io_error(path))?;
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
        if start == i || i == bytes.len() {
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
    check_declared(path, width, height)?;
    if scale == 0.0 || !scale.is_finite() {
        return Err(bad("scale must be finite and nonzero"));
    }
    // Bounded by MAX_PIXELS * 12 bytes: no overflow.
    let need = (width * height * channels * 4) as u64;
    if len < i as u64 + need {
        return Err(bad("pixel data is truncated"));
    }
    reader
        .seek(std::io::SeekFrom::Start(i as u64))
        .map_err(io_error(path))?;
    let little = scale < 0.0;
    let mut image = Image::new(width, height);
    let mut row = vec![0u8; width * channels * 4];
    for r in 0..height {
        reader.read_exact(&mut row).map_err(|e| {
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                bad("pixel data is truncated")
            } else {
                io_error(path)(e)
            }
        })?;
        let y = height - 1 - r;
        for (k, chunk) in row.chunks_exact(4).enumerate() {
            let raw = [chunk[0], chunk[1], chunk[2], chunk[3]];
            let v = if little {
                f32::from_le_bytes(raw)
            } else {
                f32::from_be_bytes(raw)
            };
            let (x, c) = (k / channels, k % channels);
            let p = &mut image.pixels[y * width + x];
            if channels == 1 {
                *p = [v; 3];
            } else {
                p[c] = v;
            }
        }
    }
    Ok(image)
}

/// Reads the first RGB(A) layer of the OpenEXR file at `path` as `f32` linear RGB. The headers
/// are read first: a layer whose declared size exceeds the limits is refused before any pixel
/// memory is allocated.
///
/// # Errors
///
/// [`ImageError::Io`] if the file cannot be opened or read or is not a regular file,
/// [`ImageError::TooLarge`] if a layer's size exceeds the limits, [`ImageError::Exr`] if it
/// is not a valid EXR or has no RGB layer.
pub fn read_exr(path: impl AsRef<Path>) -> Result<Image, ImageError> {
    let path = path.as_ref();
    let file = files::open_regular(path).map_err(io_error(path))?;
    let meta = exr::meta::MetaData::read_from_buffered(BufReader::new(&file), false)
        .map_err(|e| exr_error(path, e))?;
    for header in &meta.headers {
        check_declared(path, header.layer_size.width(), header.layer_size.height())?;
    }
    (&file).rewind().map_err(io_error(path))?;
    let decoded = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |resolution: Vec2<usize>, _channels: &exr::image::RgbaChannels| {
                // Every header was checked above; a size beyond the limits here would be a
                // decoder inconsistency: allocate nothing and let `check_size` refuse it.
                let (w, h) = (resolution.width(), resolution.height());
                if check_declared(Path::new(""), w, h).is_ok() {
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
        .first_valid_layer()
        .all_attributes()
        .from_buffered(BufReader::new(&file))
        .map_err(|e| exr_error(path, e))?;
    let image = decoded.layer_data.channel_data.pixels;
    check_size(path, image.width, image.height, image.pixels.len())?;
    Ok(image)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!(
            "chainlight-image-read-{}-{name}",
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn pfm_reads_both_byte_orders_and_rejects_garbage() {
        let dir = temp_dir("pfm");
        // 2x2 image, bottom-to-top rows.
        let mut le = b"PF\n2 2\n-1.0\n".to_vec();
        let mut be = b"PF\n2 2\n1.0\n".to_vec();
        for v in 1..=12 {
            le.extend_from_slice(&(v as f32).to_le_bytes());
            be.extend_from_slice(&(v as f32).to_be_bytes());
        }
        for (name, bytes) in [("le.pfm", &le), ("be.pfm", &be)] {
            let p = dir.join(name);
            std::fs::write(&p, bytes).unwrap();
            let img = read_image(&p).unwrap();
            assert_eq!(
                img.pixels,
                vec![
                    [7.0, 8.0, 9.0],
                    [10.0, 11.0, 12.0],
                    [1.0, 2.0, 3.0],
                    [4.0, 5.0, 6.0]
                ]
            );
        }
        let bad = dir.join("bad.pfm");
        std::fs::write(&bad, &le[..le.len() - 3]).unwrap();
        let err = read_pfm(&bad).unwrap_err();
        assert!(err.to_string().contains("truncated"), "{err}");
        std::fs::write(&bad, b"P6\n1 1\n255\n").unwrap();
        assert!(matches!(read_pfm(&bad), Err(ImageError::Pfm { .. })));
        std::fs::write(&bad, b"PF\n1 1").unwrap();
        assert!(matches!(read_pfm(&bad), Err(ImageError::Pfm { .. })));
        assert!(matches!(
            read_image(dir.join("x.png")),
            Err(ImageError::UnsupportedFormat { .. })
        ));
    }

    // A tiny EXR declaring a huge size: tests/cli_inputs.rs (the readers and every command
    // that reads images).

    #[test]
    fn pfm_and_hdr_sizes_are_checked_before_reading_pixels() {
        let dir = temp_dir("huge-pfm");
        let pfm = dir.join("huge.pfm");
        std::fs::write(&pfm, b"PF\n65536 65536\n-1.0\n\0\0\0\0").unwrap();
        let err = read_pfm(&pfm).unwrap_err();
        assert!(matches!(err, ImageError::TooLarge { .. }), "{err:?}");
        // Within the limits but longer than the file: truncated, nothing allocated for it.
        std::fs::write(&pfm, b"PF\n16384 16384\n-1.0\n\0\0\0\0").unwrap();
        let err = read_pfm(&pfm).unwrap_err();
        assert!(err.to_string().contains("truncated"), "{err}");
        let hdr = dir.join("huge.hdr");
        std::fs::write(
            &hdr,
            b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 40000 +X 40000\n\0\0\0\0",
        )
        .unwrap();
        let err = read_hdr(&hdr).unwrap_err();
        assert!(matches!(err, ImageError::TooLarge { .. }), "{err:?}");
    }

    #[cfg(unix)]
    #[test]
    fn devices_and_fifos_are_refused_without_reading() {
        let dir = temp_dir("special");
        for ext in ["pfm", "exr", "hdr"] {
            let link = dir.join(format!("zero.{ext}"));
            std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
            let err = read_image(&link).unwrap_err();
            assert!(matches!(err, ImageError::Io { .. }), "{err:?}");
            assert!(err.to_string().contains("character device"), "{err}");
        }
        let fifo = dir.join("fifo.exr");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap();
        assert!(made.success());
        // Opening a FIFO for reading blocks until a writer appears: the check must come first.
        // The read runs on its own thread so that a regression fails instead of hanging.
        let (send, receive) = std::sync::mpsc::channel();
        std::thread::spawn(move || send.send(read_image(&fifo).map(|_| ())));
        let err = receive
            .recv_timeout(std::time::Duration::from_secs(20))
            .expect("reading a FIFO blocked")
            .unwrap_err();
        assert!(err.to_string().contains("a FIFO"), "{err}");
    }
}
