//! Base-colour textures: linear RGB texels with glTF wrap modes, sampled bilinearly (or with
//! nearest-texel lookup when the glTF sampler asks for `NEAREST` magnification).

use glam::{Vec2, Vec3};

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

/// A linear RGB texture. glTF UV `(0, 0)` is the top-left corner of the image.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    width: usize,
    height: usize,
    texels: Vec<Vec3>,
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

    #[inline]
    fn texel(&self, x: i64, y: i64) -> Vec3 {
        let x = Self::wrap(x, self.width, self.wrap_s);
        let y = Self::wrap(y, self.height, self.wrap_t);
        self.texels[y * self.width + x]
    }

    /// The texture value at `uv` (non-finite coordinates read texel `(0, 0)`).
    #[must_use]
    pub fn sample(&self, uv: Vec2) -> Vec3 {
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
        match self.filter {
            TextureFilter::Nearest => self.texel(x.floor() as i64, y.floor() as i64),
            TextureFilter::Bilinear => {
                let (x, y) = (x - 0.5, y - 0.5);
                let (x0, y0) = (x.floor(), y.floor());
                let (fx, fy) = (x - x0, y - y0);
                let (x0, y0) = (x0 as i64, y0 as i64);
                let a = self.texel(x0, y0).lerp(self.texel(x0 + 1, y0), fx);
                let b = self.texel(x0, y0 + 1).lerp(self.texel(x0 + 1, y0 + 1), fx);
                a.lerp(b, fy)
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
}
