//! The structure of a MagicaVoxel `.vox` file, checked before any parser sees it: every chunk
//! whole inside its parent, `SIZE` models within MagicaVoxel's 1..=256 per axis, `XYZI` voxel
//! counts within the bytes present and every voxel inside its model. `dot_vox` reads a
//! truncated `XYZI` as fewer voxels (or none) and a 2,000,000,000³ model as any other, so a
//! hostile or damaged file would import as less than it declares, silently; here it is refused
//! with the chunk's name and byte offset.
//!
//! Layout (MagicaVoxel's file format notes): "VOX " and a version (4 + 4 bytes), then the
//! `MAIN` chunk; a chunk is its id (4 bytes), its content size N, its children's size M (u32,
//! little-endian), N content bytes, M bytes of child chunks. `SIZE` holds x, y, z (u32); the
//! `XYZI` after it holds a count and count × (x, y, z, colour index) bytes.

use super::VoxError;

/// MagicaVoxel's largest model side.
const MAX_MODEL_SIDE: u32 = 256;

fn u32_at(bytes: &[u8], at: usize) -> Option<u32> {
    bytes
        .get(at..at.checked_add(4)?)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// A chunk's id as text for messages.
fn id_text(id: &[u8]) -> String {
    id.iter()
        .map(|&c| {
            if c.is_ascii_graphic() || c == b' ' {
                char::from(c).to_string()
            } else {
                format!("\\x{c:02x}")
            }
        })
        .collect()
}

/// Checks the chunk structure of `.vox` bytes that start with "VOX " (other bytes are left
/// to the parser's own error). The error names the chunk and its byte offset.
pub fn check(bytes: &[u8]) -> Result<(), VoxError> {
    if !bytes.starts_with(b"VOX ") {
        return Ok(());
    }
    if bytes.len() < 8 + 12 {
        return Err(VoxError::Malformed(format!(
            "the file ends after {} bytes, inside its header (a .vox needs at least 20: \"VOX \", a version and the MAIN chunk's header)",
            bytes.len()
        )));
    }
    if &bytes[8..12] != b"MAIN" {
        return Err(VoxError::Malformed(format!(
            "the first chunk (byte 8) is {:?}, not MAIN",
            id_text(&bytes[8..12])
        )));
    }
    let (n, m) = (
        u32_at(bytes, 12).unwrap_or(0) as u64,
        u32_at(bytes, 16).unwrap_or(0) as u64,
    );
    let end = 20 + n + m;
    if end > bytes.len() as u64 {
        return Err(VoxError::Malformed(format!(
            "chunk MAIN at byte 8 declares {n} content and {m} children bytes, but the file ends {} bytes short (truncated)",
            end - bytes.len() as u64
        )));
    }
    let mut at = 20 + n as usize;
    let end = end as usize;
    // The last SIZE's dimensions, waiting for its XYZI.
    let mut size: Option<(usize, [u32; 3])> = None;
    while at < end {
        if end - at < 12 {
            return Err(VoxError::Malformed(format!(
                "a chunk header at byte {at} is cut off: {} bytes left of the 12 a header needs (truncated)",
                end - at
            )));
        }
        let id = &bytes[at..at + 4];
        let name = id_text(id);
        let n = u32_at(bytes, at + 4).unwrap_or(0) as u64;
        let m = u32_at(bytes, at + 8).unwrap_or(0) as u64;
        let next = at as u64 + 12 + n + m;
        if next > end as u64 {
            return Err(VoxError::Malformed(format!(
                "chunk {name} at byte {at} declares {n} content and {m} children bytes, {} more than its parent holds (truncated)",
                next - end as u64
            )));
        }
        let content = &bytes[at + 12..at + 12 + n as usize];
        match id {
            b"SIZE" => {
                if let Some((prev, _)) = size {
                    return Err(VoxError::Malformed(format!(
                        "chunk SIZE at byte {at} follows the SIZE at byte {prev} without its XYZI"
                    )));
                }
                if content.len() < 12 {
                    return Err(VoxError::Malformed(format!(
                        "chunk SIZE at byte {at} holds {} content bytes, not the 12 of a model size",
                        content.len()
                    )));
                }
                let dims = [0, 4, 8].map(|o| u32_at(content, o).unwrap_or(0));
                if dims.iter().any(|&d| d == 0 || d > MAX_MODEL_SIDE) {
                    return Err(VoxError::Malformed(format!(
                        "chunk SIZE at byte {at} declares a {} × {} × {} model; MagicaVoxel's models are 1..{MAX_MODEL_SIDE} voxels on each axis",
                        dims[0], dims[1], dims[2]
                    )));
                }
                size = Some((at, dims));
            }
            b"XYZI" => {
                let Some((_, dims)) = size.take() else {
                    return Err(VoxError::Malformed(format!(
                        "chunk XYZI at byte {at} has no SIZE chunk before it (a model's size comes first)"
                    )));
                };
                let Some(count) = u32_at(content, 0) else {
                    return Err(VoxError::Malformed(format!(
                        "chunk XYZI at byte {at} holds {} content bytes, too few for its voxel count",
                        content.len()
                    )));
                };
                let room = (content.len() as u64 - 4) / 4;
                if u64::from(count) > room {
                    return Err(VoxError::Malformed(format!(
                        "chunk XYZI at byte {at} claims {count} voxels but holds {room} ({} content bytes)",
                        content.len()
                    )));
                }
                for (k, v) in content[4..4 + 4 * count as usize]
                    .chunks_exact(4)
                    .enumerate()
                {
                    if (0..3).any(|a| u32::from(v[a]) >= dims[a]) {
                        return Err(VoxError::Malformed(format!(
                            "chunk XYZI at byte {at}: voxel {k} at ({}, {}, {}) lies outside its {} × {} × {} model",
                            v[0], v[1], v[2], dims[0], dims[1], dims[2]
                        )));
                    }
                }
            }
            _ => {}
        }
        at = next as usize;
    }
    if let Some((prev, _)) = size {
        return Err(VoxError::Malformed(format!(
            "chunk SIZE at byte {prev} has no XYZI chunk after it (the model's voxels are missing)"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chunk(id: &[u8; 4], content: &[u8], children: &[u8]) -> Vec<u8> {
        let mut c = id.to_vec();
        c.extend((content.len() as u32).to_le_bytes());
        c.extend((children.len() as u32).to_le_bytes());
        c.extend(content);
        c.extend(children);
        c
    }

    fn file(children: &[u8]) -> Vec<u8> {
        let mut f = b"VOX ".to_vec();
        f.extend(150u32.to_le_bytes());
        f.extend(chunk(b"MAIN", &[], children));
        f
    }

    fn size(x: u32, y: u32, z: u32) -> Vec<u8> {
        let c: Vec<u8> = [x, y, z].iter().flat_map(|v| v.to_le_bytes()).collect();
        chunk(b"SIZE", &c, &[])
    }

    fn xyzi(count: u32, voxels: &[[u8; 4]]) -> Vec<u8> {
        let mut c = count.to_le_bytes().to_vec();
        c.extend(voxels.iter().flatten());
        chunk(b"XYZI", &c, &[])
    }

    #[test]
    fn a_well_formed_model_passes() {
        let f = file(&[size(2, 3, 4), xyzi(2, &[[0, 0, 0, 1], [1, 2, 3, 9]])].concat());
        check(&f).unwrap();
    }

    #[test]
    fn hostile_and_damaged_files_are_refused_naming_the_chunk_and_offset() {
        let cases: Vec<(Vec<u8>, &str)> = vec![
            // The hostile file that was reported: a 2·10⁹³ model whose XYZI claims 2·10⁹ voxels and holds none.
            (
                file(
                    &[
                        size(2_000_000_000, 2_000_000_000, 2_000_000_000),
                        xyzi(2_000_000_000, &[]),
                    ]
                    .concat(),
                ),
                "chunk SIZE at byte 20 declares a 2000000000 × 2000000000 × 2000000000 model",
            ),
            (
                file(&[size(4, 4, 4), xyzi(2_000_000_000, &[])].concat()),
                "chunk XYZI at byte 44 claims 2000000000 voxels but holds 0",
            ),
            (
                file(&[size(0, 4, 4), xyzi(0, &[])].concat()),
                "declares a 0 × 4 × 4 model",
            ),
            (
                file(&[size(257, 4, 4), xyzi(0, &[])].concat()),
                "declares a 257 × 4 × 4 model",
            ),
            (
                file(&[size(4, 4, 4), xyzi(1, &[[4, 0, 0, 1]])].concat()),
                "voxel 0 at (4, 0, 0) lies outside its 4 × 4 × 4 model",
            ),
            (
                file(&[size(4, 4, 4)].concat()),
                "has no XYZI chunk after it",
            ),
            (file(&xyzi(0, &[])), "has no SIZE chunk before it"),
            (
                file(&[size(4, 4, 4), size(4, 4, 4)].concat()),
                "without its XYZI",
            ),
            (b"VOX \x96\0\0\0MA".to_vec(), "inside its header"),
        ];
        for (bytes, want) in cases {
            let e = check(&bytes).unwrap_err().to_string();
            assert!(e.contains(want), "{e:?} lacks {want:?}");
        }
        // Truncations at every length of a good file: each refused, none panics.
        let good = file(
            &[
                size(2, 2, 2),
                xyzi(3, &[[0, 0, 0, 1], [1, 1, 1, 2], [0, 1, 0, 3]]),
            ]
            .concat(),
        );
        check(&good).unwrap();
        for len in 0..good.len() {
            if len >= 4 {
                let e = check(&good[..len]).unwrap_err().to_string();
                assert!(e.contains("byte") || e.contains("bytes"), "{len}: {e}");
            }
        }
        // A chunk whose declared size runs past MAIN's end.
        let mut long = file(&size(2, 2, 2));
        let at = 20 + 4;
        long[at..at + 4].copy_from_slice(&100u32.to_le_bytes());
        let e = check(&long).unwrap_err().to_string();
        assert!(
            e.contains("chunk SIZE at byte 20 declares 100 content"),
            "{e}"
        );
    }
}
