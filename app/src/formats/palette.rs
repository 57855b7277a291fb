//! Colour palettes: in from a 256-pixel PNG (MagicaVoxel's palette files are 256 × 1 strips;
//! pixels are taken row by row) or from a .vox file's palette; out as a 256 × 1 PNG strip
//! (written atomically). A palette is the 256 colours of the colour table, in order.

use super::FormatError;
use std::path::Path;

/// Colours in a palette.
pub const SIZE: usize = 256;

/// Reads a palette from a .png or .vox file.
pub fn load(path: &Path) -> Result<Vec<[u8; 3]>, FormatError> {
    let bytes = std::fs::read(path).map_err(|e| FormatError::io(path, e))?;
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("png") => from_png(&bytes).map_err(|m| FormatError::invalid(path, m)),
        Some("vox") => {
            let data = super::vox::parse(&bytes).map_err(|e| FormatError::vox(path, e))?;
            if data.palette.len() < SIZE {
                return Err(FormatError::invalid(
                    path,
                    "the file has no 256-colour palette",
                ));
            }
            Ok(data.palette[..SIZE]
                .iter()
                .map(|c| [c.r, c.g, c.b])
                .collect())
        }
        _ => Err(FormatError::invalid(
            path,
            "a palette is read from a .png (256 pixels) or a .vox file",
        )),
    }
}

fn from_png(bytes: &[u8]) -> Result<Vec<[u8; 3]>, String> {
    let strip = png::Transformations::EXPAND | png::Transformations::STRIP_16;
    let (info, buf) = super::decode_png(bytes, strip, |w, h| {
        if w as u64 * h as u64 != SIZE as u64 {
            return Err(format!(
                "a palette image has 256 pixels (MagicaVoxel's are 256 × 1), this one is {w} × {h}"
            ));
        }
        Ok(())
    })?;
    let w = info.width;
    let channels = info.color_type.samples();
    let rows = buf[..info.buffer_size()].chunks(info.line_size);
    let mut out = Vec::with_capacity(SIZE);
    for row in rows {
        for px in row.chunks(channels).take(w as usize) {
            out.push(match channels {
                1 | 2 => [px[0]; 3],
                _ => [px[0], px[1], px[2]],
            });
        }
    }
    Ok(out)
}

/// Writes the palette as a 256 × 1 RGB PNG.
pub fn save_png(colours: &[[u8; 3]], path: &Path) -> Result<(), FormatError> {
    if colours.len() != SIZE {
        return Err(FormatError::invalid(path, "a palette has 256 colours"));
    }
    let rgb: Vec<u8> = colours.iter().flatten().copied().collect();
    crate::atomic::write_atomic(path, |w| {
        render::image::write_png_rgb8(w, SIZE as u32, 1, &rgb)
    })
    .map_err(|e| FormatError::io(path, std::io::Error::other(e)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> crate::scratch::Scratch {
        crate::scratch::Scratch::new(&format!("palette-{name}"))
    }

    #[test]
    fn a_png_strip_round_trips_and_wrong_sizes_are_named() {
        let d = temp("png");
        let colours: Vec<[u8; 3]> = (0..256)
            .map(|i| [i as u8, 255 - i as u8, (i * 7) as u8])
            .collect();
        let p = d.join("pal.png");
        save_png(&colours, &p).unwrap();
        assert_eq!(load(&p).unwrap(), colours);
        // A 16 × 16 image is 256 pixels too, read row by row.
        let mut sq = Vec::new();
        render::image::write_png_rgb8(&mut sq, 16, 16, &colours.concat()).unwrap();
        std::fs::write(d.join("sq.png"), &sq).unwrap();
        assert_eq!(load(&d.join("sq.png")).unwrap(), colours);
        let mut small = Vec::new();
        render::image::write_png_rgb8(&mut small, 8, 1, &[0; 24]).unwrap();
        std::fs::write(d.join("small.png"), &small).unwrap();
        let err = load(&d.join("small.png")).unwrap_err().to_string();
        assert!(err.contains("256 pixels") && err.contains("8 × 1"), "{err}");
        std::fs::write(d.join("bad.png"), b"not a png").unwrap();
        assert!(
            load(&d.join("bad.png"))
                .unwrap_err()
                .to_string()
                .contains("not a PNG")
        );
        assert!(load(&d.join("x.txt")).is_err());
        let _ = std::fs::remove_dir_all(d);
    }

    #[test]
    fn a_vox_files_palette_is_read() {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/vox/mmmm_chr_robot.vox");
        let pal = load(&p).unwrap();
        assert_eq!(pal.len(), 256);
        let data = super::super::vox::parse(&std::fs::read(&p).unwrap()).unwrap();
        assert_eq!(
            pal[10],
            [data.palette[10].r, data.palette[10].g, data.palette[10].b]
        );
    }
}
