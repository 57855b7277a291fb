//! Heightmap images to terrain (as vengi and Avoyd offer): a PNG, 8 or 16 bits per sample,
//! grey or colour (colour: Rec. 709 luminance of the stored values), each pixel a column —
//! pixel (x, y) of the image is column (x, z = y), +x right and +z down the image — as tall
//! as `round(value / max · height)` voxels (black: no ground). `builtin::heightmap_scene`
//! builds the terrain from what this reads. All or nothing: a file that is not a PNG, an
//! image past the largest grid, or a height out of range is refused with an error that
//! names the file and the reason.

use super::FormatError;
use std::path::Path;

/// An image's samples, one per pixel row by row, and the largest value a sample can take.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Heights {
    /// Pixels across (the grid's x).
    pub width: u32,
    /// Pixels down (the grid's z).
    pub depth: u32,
    /// One sample per pixel.
    pub values: Vec<u16>,
    /// 255 or 65535.
    pub max: u16,
}

/// Reads the PNG's samples.
pub fn read(path: &Path) -> Result<Heights, FormatError> {
    let bytes = std::fs::read(path).map_err(|e| FormatError::io(path, e))?;
    from_png(&bytes).map_err(|m| FormatError::invalid(path, m))
}

/// Reads a PNG's samples from its bytes (the reason when it cannot).
pub fn from_png(bytes: &[u8]) -> Result<Heights, String> {
    let (info, buf) = super::decode_png(bytes, png::Transformations::EXPAND, |w, h| {
        let limit = brickmap::grid::MAX_BRICKS_X * 8;
        if w > limit || h > brickmap::grid::MAX_BRICKS_Z * 8 {
            return Err(format!(
                "a heightmap is at most {limit} × {} pixels, this one is {w} × {h}",
                brickmap::grid::MAX_BRICKS_Z * 8
            ));
        }
        Ok(())
    })?;
    let (w, h) = (info.width, info.height);
    let sixteen = info.bit_depth == png::BitDepth::Sixteen;
    let channels = info.color_type.samples();
    let bytes_per = if sixteen { 2 } else { 1 };
    let sample = |px: &[u8], c: usize| -> f64 {
        if sixteen {
            f64::from(u16::from_be_bytes([px[2 * c], px[2 * c + 1]]))
        } else {
            f64::from(px[c])
        }
    };
    let mut values = Vec::with_capacity((w * h) as usize);
    for row in buf[..info.buffer_size()].chunks(info.line_size) {
        for px in row.chunks(channels * bytes_per).take(w as usize) {
            let v = if channels >= 3 {
                0.2126 * sample(px, 0) + 0.7152 * sample(px, 1) + 0.0722 * sample(px, 2)
            } else {
                sample(px, 0)
            };
            values.push(v.round() as u16);
        }
    }
    Ok(Heights {
        width: w,
        depth: h,
        values,
        max: if sixteen { u16::MAX } else { 255 },
    })
}

/// A column's height in voxels for a sample (0..=`height`).
pub fn column_height(value: u16, max: u16, height: u32) -> i32 {
    (f64::from(value) / f64::from(max) * f64::from(height)).round() as i32
}
