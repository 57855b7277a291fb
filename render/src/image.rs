//! Linear HDR images and what is done with them: PFM output for error measurement, and
//! exposure → ACES fitted tone map → sRGB 8-bit for display.

use std::io::Write;

pub mod parallel_png;

/// A linear RGB image, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear RGB radiance per pixel.
    pub pixels: Vec<[f32; 3]>,
}

impl Image {
    /// Writes a colour PFM (little-endian, rows bottom to top as the format wants).
    pub fn write_pfm(&self, out: &mut dyn Write) -> std::io::Result<()> {
        write!(out, "PF\n{} {}\n-1.0\n", self.width, self.height)?;
        for row in (0..self.height as usize).rev() {
            for p in &self.pixels[row * self.width as usize..(row + 1) * self.width as usize] {
                for c in p {
                    out.write_all(&c.to_le_bytes())?;
                }
            }
        }
        Ok(())
    }

    /// Writes an 8-bit sRGB PNG after exposure and tone mapping.
    pub fn write_png(&self, out: &mut dyn Write, exposure: f32) -> std::io::Result<()> {
        let bytes: Vec<u8> = self.to_srgb8(exposure).into_iter().flatten().collect();
        write_png_rgb8(out, self.width, self.height, &bytes)
    }

    /// Mean of every channel of every pixel.
    pub fn mean(&self) -> [f64; 3] {
        let n = self.pixels.len().max(1) as f64;
        let mut m = [0.0; 3];
        for p in &self.pixels {
            for c in 0..3 {
                m[c] += p[c] as f64 / n;
            }
        }
        m
    }

    /// Mean squared difference from `reference` over every channel of every pixel (f64), or
    /// None when the sizes differ.
    pub fn mse(&self, reference: &Image) -> Option<f64> {
        if (self.width, self.height) != (reference.width, reference.height) {
            return None;
        }
        let n = (self.pixels.len() * 3).max(1) as f64;
        Some(
            self.pixels
                .iter()
                .zip(&reference.pixels)
                .flat_map(|(a, b)| (0..3).map(move |k| (a[k] as f64 - b[k] as f64).powi(2)))
                .sum::<f64>()
                / n,
        )
    }

    /// The image resampled to `width`×`height` by bilinear interpolation between pixel
    /// centres (edges clamped), as the display pass upscales the internal resolution.
    pub fn resized_bilinear(&self, width: u32, height: u32) -> Image {
        let (sw, sh) = (self.width as i64, self.height as i64);
        let texel = |x: i64, y: i64| {
            let p = self.pixels[(y.clamp(0, sh - 1) * sw + x.clamp(0, sw - 1)) as usize];
            [p[0] as f64, p[1] as f64, p[2] as f64]
        };
        let (rx, ry) = (sw as f64 / width as f64, sh as f64 / height as f64);
        let mut pixels = Vec::with_capacity(width as usize * height as usize);
        for y in 0..height {
            let sy = (y as f64 + 0.5) * ry - 0.5;
            let (y0, fy) = (sy.floor(), sy - sy.floor());
            for x in 0..width {
                let sx = (x as f64 + 0.5) * rx - 0.5;
                let (x0, fx) = (sx.floor(), sx - sx.floor());
                let (a, b) = (texel(x0 as i64, y0 as i64), texel(x0 as i64 + 1, y0 as i64));
                let (c, d) = (
                    texel(x0 as i64, y0 as i64 + 1),
                    texel(x0 as i64 + 1, y0 as i64 + 1),
                );
                let mut out = [0f32; 3];
                for k in 0..3 {
                    let top = a[k] + (b[k] - a[k]) * fx;
                    let bottom = c[k] + (d[k] - c[k]) * fx;
                    out[k] = (top + (bottom - top) * fy) as f32;
                }
                pixels.push(out);
            }
        }
        Image {
            width,
            height,
            pixels,
        }
    }

    /// Whether every value is finite (no NaN, no infinity).
    pub fn all_finite(&self) -> bool {
        self.pixels.iter().all(|p| p.iter().all(|c| c.is_finite()))
    }

    /// 8-bit sRGB after exposure (stops) and the ACES fitted tone curve.
    pub fn to_srgb8(&self, exposure: f32) -> Vec<[u8; 3]> {
        let scale = 2f32.powf(exposure);
        self.pixels
            .iter()
            .map(|p| aces_fitted([p[0] * scale, p[1] * scale, p[2] * scale]).map(encode_srgb))
            .collect()
    }
}

/// The ACES filmic curve as fitted by Stephen Hill (sRGB input → RRT + ODT → sRGB output,
/// linear), clamped to [0, 1].
pub fn aces_fitted(c: [f32; 3]) -> [f32; 3] {
    const INPUT: [[f32; 3]; 3] = [
        [0.59719, 0.35458, 0.04823],
        [0.07600, 0.90834, 0.01566],
        [0.02840, 0.13383, 0.83777],
    ];
    const OUTPUT: [[f32; 3]; 3] = [
        [1.60475, -0.53108, -0.07367],
        [-0.10208, 1.10813, -0.00605],
        [-0.00327, -0.07276, 1.07602],
    ];
    let mul = |m: &[[f32; 3]; 3], v: [f32; 3]| {
        std::array::from_fn::<f32, 3, _>(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
    };
    let v = mul(&INPUT, c);
    let fit =
        v.map(|x| (x * (x + 0.0245786) - 0.000090537) / (x * (0.983729 * x + 0.432951) + 0.238081));
    mul(&OUTPUT, fit).map(|x| x.clamp(0.0, 1.0))
}

/// Linear [0, 1] to an sRGB byte.
pub fn encode_srgb(x: f32) -> u8 {
    let x = x.clamp(0.0, 1.0);
    let s = if x <= 0.0031308 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// Writes 8-bit RGB pixels (rows top to bottom) as a PNG.
pub fn write_png_rgb8(
    out: &mut dyn Write,
    width: u32,
    height: u32,
    rgb: &[u8],
) -> std::io::Result<()> {
    let layout = parallel_png::Layout {
        channels: 3,
        deep: false,
        srgb: false,
    };
    parallel_png::write(out, width, height, layout, rgb)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tone_curve_is_monotone_and_bounded() {
        let mut last = -1.0;
        for i in 0..1000 {
            let v = aces_fitted([i as f32 * 0.02; 3])[0];
            assert!(v >= last && (0.0..=1.0).contains(&v));
            last = v;
        }
        assert_eq!(encode_srgb(0.0), 0);
        assert_eq!(encode_srgb(1.0), 255);
    }

    #[test]
    fn png_decodes_back_to_the_tone_mapped_pixels() {
        let img = Image {
            width: 4,
            height: 3,
            pixels: (0..12).map(|i| [i as f32 * 0.1, 0.5, 2.0]).collect(),
        };
        let mut out = Vec::new();
        img.write_png(&mut out, 0.0).unwrap();
        let mut reader = png::Decoder::new(std::io::Cursor::new(out))
            .read_info()
            .unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (4, 3));
        let want: Vec<u8> = img.to_srgb8(0.0).into_iter().flatten().collect();
        assert_eq!(&buf[..info.buffer_size()], &want[..]);
    }

    #[test]
    fn pfm_has_header_and_all_pixels() {
        let img = Image {
            width: 3,
            height: 2,
            pixels: vec![[1.0, 2.0, 3.0]; 6],
        };
        let mut out = Vec::new();
        img.write_pfm(&mut out).unwrap();
        assert!(out.starts_with(b"PF\n3 2\n-1.0\n"));
        assert_eq!(out.len(), 12 + 6 * 12);
    }
}
