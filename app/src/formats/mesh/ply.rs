//! PLY, binary little-endian: four vertices per quad (x, y, z as floats; the material's
//! sRGB colour as red, green, blue bytes) and two triangles per quad. Parts are not kept
//! (PLY has one mesh).

use super::{Mesh, write_file};
use crate::formats::FormatError;
use std::path::Path;

/// Writes the mesh.
pub fn write(mesh: &Mesh, path: &Path) -> Result<(), FormatError> {
    let quads: Vec<_> = mesh.parts.iter().flat_map(|p| &p.quads).collect();
    let header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment voxbrick mesh: 1 voxel = {} units, +y up\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.voxel_size,
        quads.len() * 4,
        quads.len() * 2
    );
    let mut out = header.into_bytes();
    out.reserve(quads.len() * (4 * 15 + 2 * 13));
    let s = mesh.voxel_size;
    for q in &quads {
        let rgb = mesh.srgb(q.material);
        for c in q.corners {
            for x in [c.x, c.y, c.z] {
                out.extend_from_slice(&((f64::from(x) * s) as f32).to_le_bytes());
            }
            out.extend_from_slice(&rgb);
        }
    }
    for k in 0..quads.len() as i32 {
        let b = 4 * k;
        for tri in [[b, b + 1, b + 2], [b, b + 2, b + 3]] {
            out.push(3);
            for i in tri {
                out.extend_from_slice(&i.to_le_bytes());
            }
        }
    }
    write_file(path, &out)
}
