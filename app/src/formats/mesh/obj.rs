//! Wavefront OBJ: `NAME.obj` (positions shared between quads, one normal per side, a UV per
//! used colour at its texel's centre of the palette image, one `o` per part, `usemtl` per
//! material, quads as 4-vertex faces), `NAME.mtl` (a material per voxbrick material, each
//! textured by the palette: `Kd 1 1 1` and `map_Kd`; a metal's `Pm 1` and roughness `Pr`, a
//! lamp's `Ke` colour × strength, glass's `Ni` IOR and `Tf` colour) and `NAME_palette.png`
//! (the 256 colours, 256 × 1). Blender, Unity and Godot read this form.

use super::{Mesh, write_file};
use crate::formats::FormatError;
use brickmap::MaterialKind;
use glam::IVec3;
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

/// The side files' paths: the MTL and the palette PNG.
pub fn side_files(path: &Path) -> (std::path::PathBuf, std::path::PathBuf) {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "mesh".into());
    (
        path.with_file_name(format!("{stem}.mtl")),
        path.with_file_name(format!("{stem}_palette.png")),
    )
}

/// Writes the three files (the palette and the MTL first, the OBJ that names them last).
pub fn write(mesh: &Mesh, path: &Path) -> Result<(), FormatError> {
    let (mtl_path, png_path) = side_files(path);
    let name = |p: &Path| {
        p.file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned()
    };
    let colours: Vec<[u8; 3]> = (0..=255u8).map(|c| mesh.table.colour(c)).collect();
    crate::formats::palette::save_png(&colours, &png_path)?;
    let mut used: Vec<u8> = mesh
        .parts
        .iter()
        .flat_map(|p| p.quads.iter().map(|q| q.material))
        .collect();
    used.sort_unstable();
    used.dedup();
    let mut mtl = String::from("# voxbrick materials\n");
    for m in &used {
        let mat = mesh
            .table
            .get(*m)
            .map_err(|e| FormatError::world(path, e))?;
        let param = mesh.table.param(mat.kind, mat.param).unwrap_or(0.0);
        let c = mesh.srgb(*m).map(super::linear);
        let _ = writeln!(mtl, "\nnewmtl voxbrick_{m}");
        let _ = writeln!(mtl, "Kd 1 1 1\nKa 0 0 0\nKs 0 0 0\nd 1\nillum 1");
        let _ = writeln!(mtl, "map_Kd {}", name(&png_path));
        match mat.kind {
            MaterialKind::Lambertian => {}
            MaterialKind::Metal => {
                let _ = writeln!(mtl, "Pm 1\nPr {param}");
            }
            MaterialKind::Emissive => {
                let k = f64::from(param);
                let _ = writeln!(mtl, "Ke {} {} {}", c[0] * k, c[1] * k, c[2] * k);
            }
            MaterialKind::Dielectric => {
                let _ = writeln!(mtl, "Ni {param}\nTf {} {} {}", c[0], c[1], c[2]);
            }
        }
    }
    write_file(&mtl_path, mtl.as_bytes())?;

    let s = mesh.voxel_size;
    let mut obj = format!(
        "# voxbrick mesh: {} quads; 1 voxel = {s} units, +y up\nmtllib {}\n",
        mesh.stats().quads,
        name(&mtl_path)
    );
    let mut index: HashMap<IVec3, usize> = HashMap::new();
    let mut positions = String::new();
    for q in mesh.parts.iter().flat_map(|p| &p.quads) {
        for c in q.corners {
            let n = index.len() + 1;
            index.entry(c).or_insert_with(|| {
                let _ = writeln!(
                    positions,
                    "v {} {} {}",
                    f64::from(c.x) * s,
                    f64::from(c.y) * s,
                    f64::from(c.z) * s
                );
                n
            });
        }
    }
    obj += &positions;
    for c in 0..256 {
        let _ = writeln!(obj, "vt {} 0.5", (c as f64 + 0.5) / 256.0);
    }
    let normals = brickmap::FACES;
    for n in normals {
        let _ = writeln!(obj, "vn {} {} {}", n.x, n.y, n.z);
    }
    for part in &mesh.parts {
        let full: Vec<&str> = part
            .groups
            .iter()
            .map(String::as_str)
            .chain([part.name.as_str()])
            .collect();
        let _ = writeln!(
            obj,
            "o {}",
            full.join("/").replace(char::is_whitespace, "_")
        );
        let mut quads: Vec<_> = part.quads.iter().collect();
        quads.sort_by_key(|q| q.material);
        let mut current = None;
        for q in quads {
            if current != Some(q.material) {
                let _ = writeln!(obj, "usemtl voxbrick_{}", q.material);
                current = Some(q.material);
            }
            let t = mesh.table.get(q.material).map_or(0, |m| m.colour) as usize + 1;
            let n = normals.iter().position(|n| *n == q.normal).unwrap_or(0) + 1;
            obj += "f";
            for c in q.corners {
                let _ = write!(obj, " {}/{t}/{n}", index[&c]);
            }
            obj += "\n";
        }
    }
    write_file(path, obj.as_bytes())
}
