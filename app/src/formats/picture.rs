//! Finished pictures to image files: PNG (8 or 16 bits per channel, tone mapped as the
//! viewport shows it: exposure, the ACES fitted curve, sRGB), OpenEXR (linear, half or float)
//! and PFM (linear float, no alpha). With alpha, the picture's colour is premultiplied by it
//! (`render::finished`): EXR keeps it premultiplied (the format's rule); PNG, whose alpha is
//! straight, gets the colour divided by the alpha before the tone curve.

use render::finished::Picture;
use render::image::aces_fitted;
use std::io::Write;
use std::path::Path;

/// A picture file's format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum PictureFormat {
    /// PNG, 8 bits per channel.
    Png8,
    /// PNG, 16 bits per channel.
    Png16,
    /// OpenEXR, 16-bit floats.
    ExrHalf,
    /// OpenEXR, 32-bit floats.
    ExrFloat,
    /// Portable float map (linear RGB, no alpha).
    Pfm,
}

impl PictureFormat {
    /// The format a path's extension names (`.png`, `.exr`, `.pfm`), with 16-bit PNG or
    /// half-float EXR where `deep` / `half` ask.
    pub fn of(path: &Path, deep: bool, half: bool) -> Result<Self, String> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") if deep => Ok(Self::Png16),
            Some("png") => Ok(Self::Png8),
            Some("exr") if half => Ok(Self::ExrHalf),
            Some("exr") => Ok(Self::ExrFloat),
            Some("pfm") => Ok(Self::Pfm),
            _ => Err(format!(
                "{}: a picture is written as .png, .exr or .pfm",
                path.display()
            )),
        }
    }

    /// The usual extension.
    pub fn extension(self) -> &'static str {
        match self {
            Self::Png8 | Self::Png16 => "png",
            Self::ExrHalf | Self::ExrFloat => "exr",
            Self::Pfm => "pfm",
        }
    }

    /// A short name for menus and reports.
    pub fn label(self) -> &'static str {
        match self {
            Self::Png8 => "PNG, 8-bit",
            Self::Png16 => "PNG, 16-bit",
            Self::ExrHalf => "OpenEXR, half float",
            Self::ExrFloat => "OpenEXR, float",
            Self::Pfm => "PFM (float, no alpha)",
        }
    }

    /// Every format, for menus.
    pub const ALL: [PictureFormat; 5] = [
        Self::Png8,
        Self::Png16,
        Self::ExrHalf,
        Self::ExrFloat,
        Self::Pfm,
    ];
}

/// Writes `picture` as `format` to `path` atomically (a temporary file, fsync, rename);
/// `exposure` in stops applies to PNG only (EXR and PFM stay linear).
pub fn write_picture(
    path: &Path,
    picture: &Picture,
    format: PictureFormat,
    exposure: f32,
) -> std::io::Result<()> {
    crate::atomic::write_atomic(path, |w| match format {
        PictureFormat::Png8 | PictureFormat::Png16 => {
            write_png(w, picture, format == PictureFormat::Png16, exposure)
        }
        PictureFormat::ExrHalf | PictureFormat::ExrFloat => {
            write_exr(w, picture, format == PictureFormat::ExrHalf)
        }
        PictureFormat::Pfm => picture.image.write_pfm(w),
    })
}

/// The tone-mapped display value of a linear colour, 0..=1 (sRGB encoded).
fn display(c: [f32; 3], scale: f32) -> [f32; 3] {
    aces_fitted(c.map(|x| x * scale)).map(|x| {
        if x <= 0.0031308 {
            12.92 * x
        } else {
            1.055 * x.powf(1.0 / 2.4) - 0.055
        }
    })
}

fn write_png(
    out: &mut dyn Write,
    picture: &Picture,
    deep: bool,
    exposure: f32,
) -> std::io::Result<()> {
    let img = &picture.image;
    let scale = 2f32.powf(exposure);
    let alpha = picture.alpha.as_deref();
    let channels = if alpha.is_some() { 4 } else { 3 };
    let bytes_per_pixel = channels * if deep { 2 } else { 1 };
    let max = if deep { 65535.0 } else { 255.0 };
    let quantise = |v: f32| (v.clamp(0.0, 1.0) * max + 0.5) as u32;
    // One pixel's samples: tone mapped, straight alpha (the colour of what covers it).
    let pixel = |i: usize, out: &mut [u8]| {
        let p = img.pixels[i];
        let mut values = [0.0f32; 4];
        match alpha {
            Some(a) => {
                let a = a[i].clamp(0.0, 1.0);
                let c = if a > 0.0 { p.map(|x| x / a) } else { [0.0; 3] };
                values[..3].copy_from_slice(&display(c, scale));
                values[3] = a;
            }
            None => values[..3].copy_from_slice(&display(p, scale)),
        }
        for (k, v) in values[..channels].iter().enumerate() {
            if deep {
                out[2 * k..2 * k + 2].copy_from_slice(&(quantise(*v) as u16).to_be_bytes());
            } else {
                out[k] = quantise(*v) as u8;
            }
        }
    };
    // Tone mapping on every core: a large picture's pixels are most of its write.
    let mut bytes = vec![0u8; img.pixels.len() * bytes_per_pixel];
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let per = img.pixels.len().div_ceil(threads).max(1 << 14);
    std::thread::scope(|s| {
        for (k, part) in bytes.chunks_mut(per * bytes_per_pixel).enumerate() {
            let pixel = &pixel;
            s.spawn(move || {
                for (j, out) in part.chunks_exact_mut(bytes_per_pixel).enumerate() {
                    pixel(k * per + j, out);
                }
            });
        }
    });
    let layout = render::image::parallel_png::Layout {
        channels: channels as u8,
        deep,
        srgb: true,
    };
    render::image::parallel_png::write(out, img.width, img.height, layout, &bytes)
}

fn write_exr(out: &mut dyn Write, picture: &Picture, half: bool) -> std::io::Result<()> {
    use exr::prelude::*;
    let img = &picture.image;
    let (w, h) = (img.width as usize, img.height as usize);
    let at = |p: Vec2<usize>| p.y() * w + p.x();
    let alpha = |p: Vec2<usize>| picture.alpha.as_ref().map_or(1.0, |a| a[at(p)]);
    let mut bytes = std::io::Cursor::new(Vec::new());
    let written = match (half, picture.alpha.is_some()) {
        (true, true) => Image::from_channels(
            (w, h),
            SpecificChannels::rgba(|p: Vec2<usize>| {
                let c = img.pixels[at(p)];
                (
                    f16::from_f32(c[0]),
                    f16::from_f32(c[1]),
                    f16::from_f32(c[2]),
                    f16::from_f32(alpha(p)),
                )
            }),
        )
        .write()
        .to_buffered(&mut bytes),
        (true, false) => Image::from_channels(
            (w, h),
            SpecificChannels::rgb(|p: Vec2<usize>| {
                let c = img.pixels[at(p)];
                (
                    f16::from_f32(c[0]),
                    f16::from_f32(c[1]),
                    f16::from_f32(c[2]),
                )
            }),
        )
        .write()
        .to_buffered(&mut bytes),
        (false, true) => Image::from_channels(
            (w, h),
            SpecificChannels::rgba(|p: Vec2<usize>| {
                let c = img.pixels[at(p)];
                (c[0], c[1], c[2], alpha(p))
            }),
        )
        .write()
        .to_buffered(&mut bytes),
        (false, false) => Image::from_channels(
            (w, h),
            SpecificChannels::rgb(|p: Vec2<usize>| {
                let c = img.pixels[at(p)];
                (c[0], c[1], c[2])
            }),
        )
        .write()
        .to_buffered(&mut bytes),
    };
    written.map_err(std::io::Error::other)?;
    out.write_all(bytes.get_ref())
}

/// Numbered file names of a sequence: `dir/name.png` → `dir/name_0000.png`, … (at least
/// four digits, more when `count` needs them).
pub fn numbered(path: &Path, index: usize, count: usize) -> std::path::PathBuf {
    let digits = count.saturating_sub(1).to_string().len().max(4);
    let stem = path
        .file_stem()
        .map_or_else(|| "frame".into(), |s| s.to_string_lossy().into_owned());
    let ext = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    path.with_file_name(format!("{stem}_{index:0digits$}{ext}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_follow_the_extension_and_sequences_are_numbered() {
        let f = |p: &str, d, h| PictureFormat::of(Path::new(p), d, h);
        assert_eq!(f("a.PNG", false, false), Ok(PictureFormat::Png8));
        assert_eq!(f("a.png", true, false), Ok(PictureFormat::Png16));
        assert_eq!(f("a.exr", false, true), Ok(PictureFormat::ExrHalf));
        assert_eq!(f("a.exr", false, false), Ok(PictureFormat::ExrFloat));
        assert_eq!(f("a.pfm", false, false), Ok(PictureFormat::Pfm));
        assert!(f("a.jpg", false, false).unwrap_err().contains("a.jpg"));
        assert_eq!(
            numbered(Path::new("out/turn.png"), 7, 36),
            Path::new("out/turn_0007.png")
        );
        assert_eq!(
            numbered(Path::new("t.exr"), 12345, 20000),
            Path::new("t_12345.exr")
        );
    }

    #[test]
    fn a_large_pictures_png_is_written_in_bands_and_decodes_to_its_quantised_pixels() {
        // 1500 × 1000 RGBA at 16 bits is 12 MB: past the banded writer's threshold.
        let (w, h) = (1500u32, 1000u32);
        let n = (w * h) as usize;
        let image = render::image::Image {
            width: w,
            height: h,
            pixels: (0..n)
                .map(|i| {
                    [
                        (i % w as usize) as f32 / w as f32,
                        0.25,
                        (i / 997 % 7) as f32,
                    ]
                })
                .collect(),
        };
        let alpha: Vec<f32> = (0..n).map(|i| (i % 5) as f32 / 4.0).collect();
        let picture = render::finished::Picture {
            image,
            alpha: Some(alpha.clone()),
            samples: (1, 1),
            noise: None,
            tiles: 1,
            gpu_seconds: None,
        };
        let mut out = Vec::new();
        write_png(&mut out, &picture, true, 0.5).unwrap();
        assert!(out.len() > 8, "written");
        let mut reader = png::Decoder::new(std::io::Cursor::new(&out))
            .read_info()
            .unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (w, h));
        assert_eq!(info.color_type, png::ColorType::Rgba);
        let scale = 2f32.powf(0.5);
        for i in [0, 1, 777, n / 2 + 3, n - 1] {
            let a = alpha[i];
            let p = picture.image.pixels[i];
            let c = if a > 0.0 { p.map(|x| x / a) } else { [0.0; 3] };
            let want: Vec<u16> = display(c, scale)
                .into_iter()
                .chain([a])
                .map(|v| (v.clamp(0.0, 1.0) * 65535.0 + 0.5) as u16)
                .collect();
            let got: Vec<u16> = (0..4)
                .map(|k| u16::from_be_bytes([buf[i * 8 + 2 * k], buf[i * 8 + 2 * k + 1]]))
                .collect();
            assert_eq!(got, want, "pixel {i}");
        }
    }
}
