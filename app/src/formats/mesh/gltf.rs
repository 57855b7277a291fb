//! glTF 2.0, binary (`.glb`) or JSON with the buffer embedded as a data URI (`.gltf`): a mesh
//! per part with a primitive per material (four vertices per quad with their normal, two
//! triangles, 32-bit indices), a node per part under nodes named by its groups, and a PBR
//! material per voxbrick material — base colour (linear), a metal's roughness as
//! metallic-roughness, a lamp's colour as `emissiveFactor` with its strength in
//! `KHR_materials_emissive_strength`, glass as `KHR_materials_transmission` +
//! `KHR_materials_ior`. Metres, +y up: glTF's own conventions, one voxel `voxel_size` metres.

use super::{Mesh, write_file};
use crate::formats::FormatError;
use base64::Engine as _;
use brickmap::MaterialKind;
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::path::Path;

/// The binary buffer being built and the views and accessors into it.
#[derive(Default)]
struct Buffers {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Buffers {
    /// Appends `bytes` as a buffer view (4-byte aligned) for `target`; its index.
    fn view(&mut self, bytes: &[u8], target: u32) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views.push(json!({
            "buffer": 0,
            "byteOffset": self.bin.len(),
            "byteLength": bytes.len(),
            "target": target,
        }));
        self.bin.extend_from_slice(bytes);
        self.views.len() - 1
    }

    /// A VEC3 float accessor over `v` (with its bounds, as POSITION needs).
    fn vec3(&mut self, v: &[[f32; 3]], bounds: bool) -> usize {
        let bytes: Vec<u8> = v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes, 34962);
        let mut a = json!({
            "bufferView": view,
            "componentType": 5126,
            "count": v.len(),
            "type": "VEC3",
        });
        if bounds {
            let lo = (0..3).map(|k| v.iter().map(|p| p[k]).fold(f32::INFINITY, f32::min));
            let hi = (0..3).map(|k| v.iter().map(|p| p[k]).fold(f32::NEG_INFINITY, f32::max));
            a["min"] = json!(lo.collect::<Vec<_>>());
            a["max"] = json!(hi.collect::<Vec<_>>());
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    /// An unsigned-int index accessor.
    fn indices(&mut self, i: &[u32]) -> usize {
        let bytes: Vec<u8> = i.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes, 34963);
        self.accessors.push(json!({
            "bufferView": view,
            "componentType": 5125,
            "count": i.len(),
            "type": "SCALAR",
        }));
        self.accessors.len() - 1
    }
}

/// The material's glTF form and the extensions it uses.
fn material(mesh: &Mesh, m: u8, used: &mut Vec<&'static str>) -> Value {
    let Ok(mat) = mesh.table.get(m) else {
        return json!({ "name": format!("voxbrick_{m}") });
    };
    let param = f64::from(mesh.table.param(mat.kind, mat.param).unwrap_or(0.0));
    let c = mesh.srgb(m).map(super::linear);
    let mut out = json!({
        "name": format!("voxbrick_{m}"),
        "pbrMetallicRoughness": {
            "baseColorFactor": [c[0], c[1], c[2], 1.0],
            "metallicFactor": 0.0,
            "roughnessFactor": 1.0,
        },
    });
    let mut ext = serde_json::Map::new();
    match mat.kind {
        MaterialKind::Lambertian => {}
        MaterialKind::Metal => {
            out["pbrMetallicRoughness"]["metallicFactor"] = json!(1.0);
            out["pbrMetallicRoughness"]["roughnessFactor"] = json!(param.clamp(0.0, 1.0));
        }
        MaterialKind::Emissive => {
            out["emissiveFactor"] = json!(c);
            ext.insert(
                "KHR_materials_emissive_strength".into(),
                json!({ "emissiveStrength": param.max(0.0) }),
            );
        }
        MaterialKind::Dielectric => {
            out["pbrMetallicRoughness"]["roughnessFactor"] = json!(0.0);
            ext.insert(
                "KHR_materials_transmission".into(),
                json!({ "transmissionFactor": 1.0 }),
            );
            ext.insert("KHR_materials_ior".into(), json!({ "ior": param }));
        }
    }
    for k in ext.keys() {
        let name: &'static str = match k.as_str() {
            "KHR_materials_emissive_strength" => "KHR_materials_emissive_strength",
            "KHR_materials_transmission" => "KHR_materials_transmission",
            _ => "KHR_materials_ior",
        };
        if !used.contains(&name) {
            used.push(name);
        }
    }
    if !ext.is_empty() {
        out["extensions"] = Value::Object(ext);
    }
    out
}

/// The glTF document (JSON) and its binary buffer.
pub fn document(mesh: &Mesh) -> (Value, Vec<u8>) {
    let mut buffers = Buffers::default();
    let mut used_ext = Vec::new();
    let mut materials = Vec::new();
    let mut material_index: BTreeMap<u8, usize> = BTreeMap::new();
    let mut meshes = Vec::new();
    let mut nodes: Vec<Value> = Vec::new();
    let mut roots = Vec::new();
    // Group nodes by their path, created as parts need them.
    let mut groups: BTreeMap<Vec<String>, usize> = BTreeMap::new();
    let s = mesh.voxel_size;
    for part in &mesh.parts {
        let mut by_material: BTreeMap<u8, Vec<&super::Quad>> = BTreeMap::new();
        for q in &part.quads {
            by_material.entry(q.material).or_default().push(q);
        }
        let mut primitives = Vec::new();
        for (m, quads) in by_material {
            let mi = *material_index.entry(m).or_insert_with(|| {
                materials.push(material(mesh, m, &mut used_ext));
                materials.len() - 1
            });
            let mut pos = Vec::with_capacity(quads.len() * 4);
            let mut nor = Vec::with_capacity(quads.len() * 4);
            let mut idx = Vec::with_capacity(quads.len() * 6);
            for q in quads {
                let b = pos.len() as u32;
                for c in q.corners {
                    pos.push([c.x, c.y, c.z].map(|x| (f64::from(x) * s) as f32));
                    nor.push([q.normal.x, q.normal.y, q.normal.z].map(|x| x as f32));
                }
                idx.extend_from_slice(&[b, b + 1, b + 2, b, b + 2, b + 3]);
            }
            let position = buffers.vec3(&pos, true);
            let normal = buffers.vec3(&nor, false);
            let indices = buffers.indices(&idx);
            primitives.push(json!({
                "attributes": { "POSITION": position, "NORMAL": normal },
                "indices": indices,
                "material": mi,
                "mode": 4,
            }));
        }
        let mut node = json!({ "name": part.name });
        if let Some((r, t)) = part.transform {
            // Column-major; the translation in the file's units.
            let mut m = [0.0f64; 16];
            for (row, cols) in r.iter().enumerate() {
                for (col, v) in cols.iter().enumerate() {
                    m[col * 4 + row] = f64::from(*v);
                }
            }
            m[12] = f64::from(t.x) * s;
            m[13] = f64::from(t.y) * s;
            m[14] = f64::from(t.z) * s;
            m[15] = 1.0;
            node["matrix"] = json!(m);
        }
        if !primitives.is_empty() {
            meshes.push(json!({ "name": part.name, "primitives": primitives }));
            node["mesh"] = json!(meshes.len() - 1);
        }
        nodes.push(node);
        let me = nodes.len() - 1;
        // Its groups, outermost first: each a node holding the next.
        let mut parent: Option<usize> = None;
        for depth in 1..=part.groups.len() {
            let path = part.groups[..depth].to_vec();
            let g = match groups.get(&path) {
                Some(g) => *g,
                None => {
                    nodes.push(json!({ "name": path[depth - 1], "children": [] }));
                    let g = nodes.len() - 1;
                    groups.insert(path, g);
                    match parent {
                        Some(p) => nodes[p]["children"].as_array_mut().unwrap().push(json!(g)),
                        None => roots.push(g),
                    }
                    g
                }
            };
            parent = Some(g);
        }
        match parent {
            Some(p) => nodes[p]["children"].as_array_mut().unwrap().push(json!(me)),
            None => roots.push(me),
        }
    }
    while !buffers.bin.len().is_multiple_of(4) {
        buffers.bin.push(0);
    }
    let mut doc = json!({
        "asset": { "version": "2.0", "generator": "voxbrick" },
        "scene": 0,
        "scenes": [{ "name": "voxbrick", "nodes": roots }],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "accessors": buffers.accessors,
        "bufferViews": buffers.views,
        "buffers": [{ "byteLength": buffers.bin.len() }],
    });
    if !used_ext.is_empty() {
        doc["extensionsUsed"] = json!(used_ext);
    }
    (doc, buffers.bin)
}

/// Writes the mesh as `.glb` (`binary`) or `.gltf` with the buffer as a data URI.
pub fn write(mesh: &Mesh, path: &Path, binary: bool) -> Result<(), FormatError> {
    let (mut doc, bin) = document(mesh);
    if !binary {
        let uri = format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&bin)
        );
        doc["buffers"][0]["uri"] = json!(uri);
        let text =
            serde_json::to_string(&doc).map_err(|e| FormatError::invalid(path, e.to_string()))?;
        return write_file(path, text.as_bytes());
    }
    let mut text =
        serde_json::to_vec(&doc).map_err(|e| FormatError::invalid(path, e.to_string()))?;
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let total = 12 + 8 + text.len() + 8 + bin.len();
    if total > u32::MAX as usize {
        return Err(FormatError::invalid(
            path,
            format!(
                "{total} bytes: a .glb holds at most 4 GiB (merge faces, or write .obj or .ply)"
            ),
        ));
    }
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x4E4F_534Au32.to_le_bytes());
    out.extend_from_slice(&text);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x004E_4942u32.to_le_bytes());
    out.extend_from_slice(&bin);
    write_file(path, &out)
}
