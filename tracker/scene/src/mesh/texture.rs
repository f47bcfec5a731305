//! Diffuse textures: linear RGB texels with wrap-around bilinear sampling.

/// Converts an 8-bit sRGB value to linear `[0, 1]`.
pub fn srgb_to_linear(c: u8) -> f32 {
    let c = f32::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Maps a texture coordinate into `[0, 1)` (repeat addressing); non-finite coordinates map to 0.
#[inline]
pub fn wrap_unit(t: f32) -> f32 {
    // Beyond 2^23 every f32 is an integer (fraction 0); NaN fails the comparison. Truncation avoids a libm call.
    if t.is_nan() || t.abs() >= 8_388_608.0 {
        return 0.0;
    }
    let f = t - (t as i32) as f32;
    if f < 0.0 { f + 1.0 } else { f }
}

/// A diffuse texture in linear RGB (`[0, 1]`), row-major, first row = top of the image (`v = 1` in OBJ coordinates).
///
/// Invariant: `texels.len() == width * height`, both non-zero.
#[derive(Debug, Clone, PartialEq)]
pub struct Texture {
    width: u32,
    height: u32,
    texels: Vec<[f32; 3]>,
}

impl Texture {
    /// Builds a texture from 8-bit sRGB RGB bytes (row-major, top row first, 3 bytes per pixel). `None` if the size
    /// is zero or does not match the data.
    pub fn from_srgb8(width: u32, height: u32, rgb: &[u8]) -> Option<Self> {
        let n = (width as usize).checked_mul(height as usize)?;
        if n == 0 || rgb.len() != n.checked_mul(3)? {
            return None;
        }
        let lut: Vec<f32> = (0..=255u8).map(srgb_to_linear).collect();
        let texels = rgb
            .chunks_exact(3)
            .map(|p| [lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]])
            .collect();
        Some(Self {
            width,
            height,
            texels,
        })
    }

    /// Builds a texture from linear RGB texels. `None` if the size is zero or does not match.
    pub fn from_linear(width: u32, height: u32, texels: Vec<[f32; 3]>) -> Option<Self> {
        let n = (width as usize).checked_mul(height as usize)?;
        (n != 0 && texels.len() == n).then_some(Self {
            width,
            height,
            texels,
        })
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }
    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }
    /// Linear RGB texels, row-major, top row first.
    pub fn texels(&self) -> &[[f32; 3]] {
        &self.texels
    }

    /// Bilinear sample at OBJ texture coordinates `(u, v)` (`v` up), wrapping (repeat) outside `[0, 1)`.
    /// Texel centres sit at `(i + 0.5) / width`.
    pub fn sample_bilinear(&self, u: f32, v: f32) -> [f32; 3] {
        let w = self.width as usize;
        let h = self.height as usize;
        let x = wrap_unit(u) * self.width as f32 - 0.5;
        let y = (1.0 - wrap_unit(v)) * self.height as f32 - 0.5;
        let x0f = x.floor();
        let y0f = y.floor();
        let fx = x - x0f;
        let fy = y - y0f;
        let wrap = |i: f32, n: usize| -> usize {
            let n_i = n as i64;
            // Saturating cast: huge coordinates stay finite; rem_euclid keeps the index in range.
            ((i as i64).rem_euclid(n_i)) as usize
        };
        let x0 = wrap(x0f, w);
        let x1 = wrap(x0f + 1.0, w);
        let y0 = wrap(y0f, h);
        let y1 = wrap(y0f + 1.0, h);
        let t = |xi: usize, yi: usize| self.texels[yi * w + xi];
        let (a, b, c, d) = (t(x0, y0), t(x1, y0), t(x0, y1), t(x1, y1));
        let mut out = [0.0; 3];
        for k in 0..3 {
            let top = a[k] + (b[k] - a[k]) * fx;
            let bottom = c[k] + (d[k] - c[k]) * fx;
            out[k] = top + (bottom - top) * fy;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_endpoints() {
        assert_eq!(srgb_to_linear(0), 0.0);
        assert!((srgb_to_linear(255) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(188) - 0.5).abs() < 0.01);
    }

    #[test]
    fn bilinear_interpolates_and_wraps() {
        // 2x1 texture: left black, right white.
        let t = Texture::from_linear(2, 1, vec![[0.0; 3], [1.0; 3]]).unwrap();
        assert_eq!(t.sample_bilinear(0.25, 0.5)[0], 0.0);
        assert_eq!(t.sample_bilinear(0.75, 0.5)[0], 1.0);
        assert!((t.sample_bilinear(0.5, 0.5)[0] - 0.5).abs() < 1e-6);
        // Wrapping: u = 1.0 lies halfway between the right texel and the (wrapped) left one.
        assert!((t.sample_bilinear(1.0, 0.5)[0] - 0.5).abs() < 1e-6);
        assert_eq!(t.sample_bilinear(-0.25, 0.5)[0], 1.0);
        assert!(t.sample_bilinear(f32::MAX, 0.5)[0].is_finite());
        assert!(Texture::from_srgb8(2, 2, &[0; 11]).is_none());
    }
}
