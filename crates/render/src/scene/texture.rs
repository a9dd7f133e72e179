//! Material textures: linear RGB texels (decoded from sRGB for colour textures, kept as stored
//! for data textures such as metallic-roughness and normal maps) with an optional alpha
//! channel, glTF wrap modes, sampled bilinearly (or with nearest-texel lookup when the glTF
//! sampler asks for `NEAREST` magnification).

use glam::{Vec2, Vec3};

/// What a texture lookup blends ([`Texture::footprint`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Footprint {
    /// Texels `[t00, t10, t01, t11]` (all four the same for nearest lookup).
    pub(crate) texels: [Vec3; 4],
    /// Texel-space origin `(x0, y0)` of the bilinear cell.
    pub(crate) origin: [f64; 2],
    /// Texture size `(width, height)`.
    pub(crate) size: [f64; 2],
    /// False for nearest lookup.
    pub(crate) bilinear: bool,
}

/// How texture coordinates outside `[0, 1]` are mapped back (glTF `sampler.wrapS/wrapT`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum WrapMode {
    /// Tile the texture (glTF `REPEAT`, 10497, the default).
    #[default]
    Repeat,
    /// Clamp to the edge texel (glTF `CLAMP_TO_EDGE`, 33071).
    ClampToEdge,
    /// Tile with every other copy mirrored (glTF `MIRRORED_REPEAT`, 33648).
    MirroredRepeat,
}

/// How a texture is reconstructed between texel centres.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum TextureFilter {
    /// Bilinear interpolation of the four nearest texels (the default; no mipmapping).
    #[default]
    Bilinear,
    /// The nearest texel (glTF `magFilter = NEAREST`, 9728).
    Nearest,
}

/// A linear RGB texture with an optional alpha channel. glTF UV `(0, 0)` is the top-left
/// corner of the image.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    width: usize,
    height: usize,
    texels: Vec<Vec3>,
    /// Per-texel alpha (linear, in `[0, 1]`), or empty: opaque everywhere.
    alpha: Vec<f32>,
    /// Wrap mode along u.
    pub wrap_s: WrapMode,
    /// Wrap mode along v.
    pub wrap_t: WrapMode,
    /// Reconstruction filter.
    pub filter: TextureFilter,
}

/// The sRGB electro-optical transfer function: an 8-bit sRGB-encoded value to linear.
#[must_use]
pub fn srgb_to_linear(v: u8) -> f32 {
    let c = f32::from(v) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl Texture {
    /// A texture from linear RGB texels (row-major, top row first), or `None` if the size is
    /// zero or does not match `texels.len()`.
    #[must_use]
    pub fn new(width: usize, height: usize, texels: Vec<Vec3>) -> Option<Self> {
        (width > 0 && height > 0 && width.checked_mul(height) == Some(texels.len())).then_some(
            Self {
                width,
                height,
                texels,
                alpha: Vec::new(),
                wrap_s: WrapMode::Repeat,
                wrap_t: WrapMode::Repeat,
                filter: TextureFilter::Bilinear,
            },
        )
    }

    /// A texture from 8-bit sRGB-encoded RGB triples (base-colour textures are sRGB in glTF).
    #[must_use]
    pub fn from_srgb8(width: usize, height: usize, rgb: &[u8]) -> Option<Self> {
        if width.checked_mul(height)?.checked_mul(3)? != rgb.len() {
            return None;
        }
        let mut lut = [0.0f32; 256];
        for (i, l) in lut.iter_mut().enumerate() {
            *l = srgb_to_linear(i as u8);
        }
        let texels = rgb
            .chunks_exact(3)
            .map(|c| Vec3::new(lut[c[0] as usize], lut[c[1] as usize], lut[c[2] as usize]))
            .collect();
        Self::new(width, height, texels)
    }

    /// A texture from 8-bit RGBA quadruples: RGB sRGB-encoded if `srgb` (colour textures) or
    /// linear otherwise (data textures: metallic-roughness, normal maps); alpha is always
    /// linear (glTF). The alpha channel is kept only if `keep_alpha` and some texel is not
    /// fully opaque.
    #[must_use]
    pub fn from_rgba8(
        width: usize,
        height: usize,
        rgba: &[u8],
        srgb: bool,
        keep_alpha: bool,
    ) -> Option<Self> {
        if width.checked_mul(height)?.checked_mul(4)? != rgba.len() {
            return None;
        }
        let mut lut = [0.0f32; 256];
        for (i, l) in lut.iter_mut().enumerate() {
            *l = if srgb {
                srgb_to_linear(i as u8)
            } else {
                i as f32 / 255.0
            };
        }
        let texels = rgba
            .chunks_exact(4)
            .map(|c| Vec3::new(lut[c[0] as usize], lut[c[1] as usize], lut[c[2] as usize]))
            .collect();
        let mut t = Self::new(width, height, texels)?;
        if keep_alpha && rgba.chunks_exact(4).any(|c| c[3] != 255) {
            t.alpha = rgba
                .chunks_exact(4)
                .map(|c| f32::from(c[3]) / 255.0)
                .collect();
        }
        Some(t)
    }

    /// The texture with per-texel alpha `alpha` (row-major, top row first; values are clamped
    /// to `[0, 1]`, NaN reads as 1), or `None` if the length does not match the texel count.
    #[must_use]
    pub fn with_alpha(mut self, alpha: Vec<f32>) -> Option<Self> {
        if alpha.len() != self.texels.len() {
            return None;
        }
        self.alpha = alpha
            .into_iter()
            .map(|a| if a.is_nan() { 1.0 } else { a.clamp(0.0, 1.0) })
            .collect();
        Some(self)
    }

    /// True if the texture has an alpha channel (otherwise [`Texture::sample_alpha`] is 1).
    #[must_use]
    pub fn has_alpha(&self) -> bool {
        !self.alpha.is_empty()
    }

    /// Width in texels.
    #[must_use]
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in texels.
    #[must_use]
    pub fn height(&self) -> usize {
        self.height
    }

    #[inline]
    fn wrap(i: i64, n: usize, mode: WrapMode) -> usize {
        let n = n as i64;
        let j = match mode {
            WrapMode::Repeat => i.rem_euclid(n),
            WrapMode::ClampToEdge => i.clamp(0, n - 1),
            WrapMode::MirroredRepeat => {
                let k = i.rem_euclid(2 * n);
                if k < n {
                    k
                } else {
                    2 * n - 1 - k
                }
            }
        };
        j as usize
    }

    /// The index of texel `(x, y)` after wrapping.
    #[inline]
    fn index(&self, x: i64, y: i64) -> usize {
        let x = Self::wrap(x, self.width, self.wrap_s);
        let y = Self::wrap(y, self.height, self.wrap_t);
        y * self.width + x
    }

    /// The texels and texel-space origin a lookup at `uv` blends, for code that restates the
    /// bilinear filter over another scalar type (`crate::bdpt::diff`): the colour is
    /// `lerp(lerp(t00, t10, fx), lerp(t01, t11, fx), fy)` with `fx = uv.x * width - 0.5 - x0`,
    /// `fy = uv.y * height - 0.5 - y0` (bilinear), or `t00` (nearest). `None` for coordinates
    /// the lookup reduces by whole periods (`|uv| > 1e6`) or non-finite ones.
    #[must_use]
    pub(crate) fn footprint(&self, uv: Vec2) -> Option<Footprint> {
        if !uv.is_finite() || uv.abs().max_element() > 1e6 {
            return None;
        }
        let x = uv.x * self.width as f32;
        let y = uv.y * self.height as f32;
        let at = |x: i64, y: i64| self.texels[self.index(x, y)];
        let size = [self.width as f64, self.height as f64];
        Some(match self.filter {
            TextureFilter::Nearest => {
                let t = at(x.floor() as i64, y.floor() as i64);
                Footprint {
                    texels: [t; 4],
                    origin: [0.0; 2],
                    size,
                    bilinear: false,
                }
            }
            TextureFilter::Bilinear => {
                let (x0, y0) = ((x - 0.5).floor(), (y - 0.5).floor());
                let (i, j) = (x0 as i64, y0 as i64);
                Footprint {
                    texels: [at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)],
                    origin: [f64::from(x0), f64::from(y0)],
                    size,
                    bilinear: true,
                }
            }
        })
    }

    /// The texture value at `uv` (non-finite coordinates read texel `(0, 0)`).
    #[must_use]
    pub fn sample(&self, uv: Vec2) -> Vec3 {
        self.filtered(uv, |i| self.texels[i], Vec3::lerp)
    }

    /// The alpha at `uv`, filtered like [`Texture::sample`]; 1 without an alpha channel.
    #[must_use]
    pub fn sample_alpha(&self, uv: Vec2) -> f32 {
        if self.alpha.is_empty() {
            return 1.0;
        }
        self.filtered(uv, |i| self.alpha[i], |a, b, t| a + (b - a) * t)
    }

    /// Reconstructs the texel values `fetch(index)` at `uv` with the texture's filter and
    /// wrap modes.
    #[inline]
    fn filtered<T: Copy>(
        &self,
        uv: Vec2,
        fetch: impl Fn(usize) -> T,
        lerp: impl Fn(T, T, f32) -> T,
    ) -> T {
        let uv = if uv.is_finite() { uv } else { Vec2::ZERO };
        // Keep the coordinates in a range where f32 -> i64 is exact enough: repeat modes are
        // periodic, so reducing by whole periods of 2 changes nothing.
        let reduce = |t: f32| {
            if t.abs() > 1e6 {
                t - (t / 2.0).floor() * 2.0
            } else {
                t
            }
        };
        let x = reduce(uv.x) * self.width as f32;
        let y = reduce(uv.y) * self.height as f32;
        let at = |x: i64, y: i64| fetch(self.index(x, y));
        match self.filter {
            TextureFilter::Nearest => at(x.floor() as i64, y.floor() as i64),
            TextureFilter::Bilinear => {
                let (x, y) = (x - 0.5, y - 0.5);
                let (x0, y0) = (x.floor(), y.floor());
                let (fx, fy) = (x - x0, y - y0);
                let (x0, y0) = (x0 as i64, y0 as i64);
                let a = lerp(at(x0, y0), at(x0 + 1, y0), fx);
                let b = lerp(at(x0, y0 + 1), at(x0 + 1, y0 + 1), fx);
                lerp(a, b, fy)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker() -> Texture {
        Texture::new(2, 2, vec![Vec3::ZERO, Vec3::ONE, Vec3::ONE, Vec3::ZERO]).unwrap()
    }

    #[test]
    fn nearest_and_bilinear() {
        let mut t = checker();
        t.filter = TextureFilter::Nearest;
        assert_eq!(t.sample(Vec2::new(0.25, 0.25)), Vec3::ZERO);
        assert_eq!(t.sample(Vec2::new(0.75, 0.25)), Vec3::ONE);
        assert_eq!(t.sample(Vec2::new(1.25, 0.25)), Vec3::ZERO); // repeat
        t.filter = TextureFilter::Bilinear;
        assert_eq!(t.sample(Vec2::new(0.25, 0.25)), Vec3::ZERO); // texel centre
        let mid = t.sample(Vec2::new(0.5, 0.25));
        assert!((mid - Vec3::splat(0.5)).abs().max_element() < 1e-6);
    }

    #[test]
    fn wrap_modes_and_bad_coordinates() {
        let mut t = checker();
        t.filter = TextureFilter::Nearest;
        t.wrap_s = WrapMode::ClampToEdge;
        assert_eq!(t.sample(Vec2::new(7.9, 0.25)), Vec3::ONE);
        assert_eq!(t.sample(Vec2::new(-7.9, 0.25)), Vec3::ZERO);
        t.wrap_s = WrapMode::MirroredRepeat;
        assert_eq!(t.sample(Vec2::new(1.25, 0.25)), Vec3::ONE);
        for uv in [
            Vec2::splat(f32::NAN),
            Vec2::splat(f32::INFINITY),
            Vec2::splat(-3e38),
            Vec2::splat(1e30),
        ] {
            let v = t.sample(uv);
            assert!(v.is_finite());
        }
    }

    #[test]
    fn srgb_decoding() {
        let t = Texture::from_srgb8(1, 1, &[255, 0, 188]).unwrap();
        let v = t.sample(Vec2::ZERO);
        assert!((v.x - 1.0).abs() < 1e-6 && v.y == 0.0);
        assert!((v.z - 0.5).abs() < 0.01, "{}", v.z);
        assert!(Texture::from_srgb8(2, 1, &[0; 3]).is_none());
        assert!(Texture::new(0, 1, vec![]).is_none());
    }

    #[test]
    fn rgba_linear_and_alpha() {
        // Linear data: 188 stays 188/255 (sRGB decoding would give about 0.5).
        let t = Texture::from_rgba8(1, 1, &[255, 0, 188, 255], false, true).unwrap();
        assert!((t.sample(Vec2::ZERO).z - 188.0 / 255.0).abs() < 1e-6);
        assert!(!t.has_alpha(), "an opaque image keeps no alpha channel");
        assert_eq!(t.sample_alpha(Vec2::ZERO), 1.0);
        let s = Texture::from_rgba8(1, 1, &[255, 0, 188, 255], true, true).unwrap();
        assert!((s.sample(Vec2::ZERO).z - 0.5).abs() < 0.01);
        // Two texels, left transparent, right opaque.
        let mut a = Texture::from_rgba8(2, 1, &[9, 9, 9, 0, 9, 9, 9, 255], true, true).unwrap();
        a.filter = TextureFilter::Nearest;
        assert!(a.has_alpha());
        assert_eq!(a.sample_alpha(Vec2::new(0.25, 0.5)), 0.0);
        assert_eq!(a.sample_alpha(Vec2::new(0.75, 0.5)), 1.0);
        a.filter = TextureFilter::Bilinear;
        a.wrap_s = WrapMode::ClampToEdge;
        assert!((a.sample_alpha(Vec2::new(0.5, 0.5)) - 0.5).abs() < 1e-6);
        let no = Texture::from_rgba8(2, 1, &[9, 9, 9, 0, 9, 9, 9, 255], true, false).unwrap();
        assert!(!no.has_alpha());
        assert!(Texture::from_rgba8(2, 1, &[0; 4], true, true).is_none());
        let w = checker()
            .with_alpha(vec![f32::NAN, 2.0, -1.0, 0.5])
            .unwrap();
        assert!(w.has_alpha());
        assert!(checker().with_alpha(vec![1.0]).is_none());
    }
}
