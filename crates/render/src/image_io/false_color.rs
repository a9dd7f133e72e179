//! False-colour error maps: one value per pixel coloured with viridis on a linear or
//! logarithmic scale.

use std::path::Path;

use super::{check_size, write_rgb8_png, ImageError};

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

        let dir =
            std::env::temp_dir().join(format!("chainlight-false-color-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("errors.png");
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
