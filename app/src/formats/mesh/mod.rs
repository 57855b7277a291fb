//! Meshes out: a scene's voxels as quads (`greedy`: the faces that show, merged into
//! rectangles of one material, or one quad per face), written as Wavefront OBJ (with its MTL
//! and the colour table as a 256 × 1 PNG, UVs at texel centres), glTF 2.0 (`.glb` binary or
//! `.gltf` with the buffer embedded; PBR materials) or PLY (binary, vertex colours).
//!
//! Units and axes: one voxel is `voxel_size` units (1 by default; glTF reads them as metres),
//! +y is up, as in voxbrick and glTF; a right-handed frame. Quads wind counter-clockwise seen
//! from outside. Merged (the default) is the scene as shown, one mesh; per object is each
//! drawn object's own model with its placement applied (world coordinates), named by the
//! object and, in glTF, under nodes named by its groups. Hidden objects are left out.
//! Every file is written atomically (temporary file, fsync, rename).

pub mod gltf;
pub mod greedy;
pub mod obj;
pub mod ply;

use super::FormatError;
use crate::scene::Scene;
use brickmap::objects::{NodeId, NodeKind};
use brickmap::{MaterialKind, MaterialTable};
use glam::IVec3;
pub use greedy::Quad;
use std::path::Path;

/// How a mesh is made (also the editor's File → Mesh options, kept in its settings).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct MeshOptions {
    /// Merge coplanar faces of one material into rectangles (T-junctions where a long edge
    /// meets short ones); off: one quad per voxel face (watertight).
    pub greedy: bool,
    /// One part per drawn object (else the scene as shown, one part).
    pub per_object: bool,
    /// Units per voxel.
    pub voxel_size: f64,
    /// Per object in glTF: each object's mesh in its model's frame (the pivot at the origin)
    /// and its placement as the node's matrix, instead of applied (OBJ and PLY apply it).
    pub keep_transforms: bool,
}

impl Default for MeshOptions {
    fn default() -> Self {
        Self {
            greedy: true,
            per_object: false,
            voxel_size: 1.0,
            keep_transforms: false,
        }
    }
}

/// A named piece of the mesh: an object (with the names of the groups above it, root
/// first) or the merged scene.
#[derive(Clone, Debug)]
pub struct Part {
    /// Its name.
    pub name: String,
    /// The groups above it, outermost first (empty when merged or at the root).
    pub groups: Vec<String>,
    /// Its quads, in world voxel coordinates — or, with `transform`, in its own frame.
    pub quads: Vec<Quad>,
    /// Its placement kept: the rotation (a signed permutation, rows) and the translation in
    /// voxels that carry its quads into the world.
    pub transform: Option<([[i32; 3]; 3], IVec3)>,
}

/// A scene as quads, with the table its materials index.
pub struct Mesh {
    /// The parts.
    pub parts: Vec<Part>,
    /// The material table.
    pub table: MaterialTable,
    /// Units per voxel.
    pub voxel_size: f64,
}

/// What an export wrote.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MeshStats {
    /// Parts (objects, or 1).
    pub parts: usize,
    /// Quads.
    pub quads: usize,
    /// Triangles (two per quad).
    pub triangles: usize,
}

impl Mesh {
    /// Counts.
    pub fn stats(&self) -> MeshStats {
        let quads = self.parts.iter().map(|p| p.quads.len()).sum();
        MeshStats {
            parts: self.parts.len(),
            quads,
            triangles: quads * 2,
        }
    }

    /// Each material's colour as sRGB (through its colour index).
    pub fn srgb(&self, material: u8) -> [u8; 3] {
        let colour = self.table.get(material).map_or(0, |m| m.colour);
        self.table.colour(colour)
    }
}

/// Which materials let light through (their faces against other materials show).
fn see_through(table: &MaterialTable) -> [bool; 256] {
    std::array::from_fn(|m| {
        table
            .get(m as u8)
            .is_ok_and(|x| x.kind == MaterialKind::Dielectric)
    })
}

/// The scene's mesh.
pub fn build(scene: &Scene, options: &MeshOptions) -> Mesh {
    build_watched(scene, options, &|_| true).expect("never stopped")
}

/// [`build`], telling `watch` the part done (0..1) as it goes; None when it says stop.
pub fn build_watched(
    scene: &Scene,
    options: &MeshOptions,
    watch: &dyn Fn(f64) -> bool,
) -> Option<Mesh> {
    let table = scene.world.materials().clone();
    let clear = see_through(&table);
    let parts = if options.per_object {
        let objects = scene.objects();
        let tree = objects.tree();
        let drawn = tree.drawn();
        let n = drawn.len().max(1) as f64;
        let mut parts = Vec::new();
        for (k, d) in drawn.into_iter().enumerate() {
            let part = |f: f64| watch((k as f64 + f) / n);
            if !part(0.0) {
                return None;
            }
            let local = match objects.model(d.model) {
                Some(model) => greedy::quads(model, &clear, options.greedy, &part)?,
                None => continue,
            };
            parts.extend(placed_part(
                tree,
                objects.model(d.model),
                &d,
                local,
                options,
            ));
        }
        parts
    } else {
        let view = scene.world.read();
        vec![Part {
            name: "scene".into(),
            groups: Vec::new(),
            quads: greedy::quads(&view, &clear, options.greedy, watch)?,
            transform: None,
        }]
    };
    Some(Mesh {
        parts,
        table,
        voxel_size: options.voxel_size,
    })
}

/// A drawn object's part: its model's `local` quads placed (or kept in the model's frame,
/// with the placement as the part's transform, for glTF with `keep_transforms`).
fn placed_part(
    tree: &brickmap::objects::ObjectTree,
    model: Option<&brickmap::objects::Model>,
    d: &brickmap::objects::Drawn,
    local: Vec<Quad>,
    options: &MeshOptions,
) -> Option<Part> {
    let model = model?;
    let size = model.size();
    let rot = d.placement.rot;
    let half = size.div_euclid(IVec3::splat(2));
    // A corner p of the model lands at R·(p − ⌊s/2⌋) + t (the pivot rule).
    let place = |p: IVec3| rot.apply(p - half) + d.placement.t;
    let node = tree.node(d.node).ok()?;
    if options.keep_transforms {
        return Some(Part {
            name: node.name.clone(),
            groups: groups_above(tree, d.node),
            quads: local
                .into_iter()
                .map(|q| Quad {
                    corners: q.corners.map(|p| p - half),
                    ..q
                })
                .collect(),
            transform: Some((rot.matrix(), d.placement.t)),
        });
    }
    let quads = local
        .into_iter()
        .map(|q| {
            let mut corners = q.corners.map(place);
            if rot.is_reflection() {
                corners.reverse();
            }
            Quad {
                corners,
                normal: rot.apply(q.normal),
                material: q.material,
            }
        })
        .collect();
    Some(Part {
        name: node.name.clone(),
        groups: groups_above(tree, d.node),
        quads,
        transform: None,
    })
}

/// The names of the groups above `node`, outermost first (the root left out).
fn groups_above(tree: &brickmap::objects::ObjectTree, node: NodeId) -> Vec<String> {
    let mut out = Vec::new();
    let mut at = tree.node(node).ok().and_then(|n| n.parent());
    while let Some(id) = at {
        if id == brickmap::objects::ObjectTree::ROOT {
            break;
        }
        let Ok(n) = tree.node(id) else { break };
        if matches!(n.kind, NodeKind::Group { .. }) {
            out.push(n.name.clone());
        }
        at = n.parent();
    }
    out.reverse();
    out
}

/// The mesh formats, by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront `.obj` (+ `.mtl` + the palette PNG).
    Obj,
    /// glTF binary `.glb`.
    Glb,
    /// glTF JSON `.gltf`, the buffer embedded.
    Gltf,
    /// `.ply`, binary, vertex colours.
    Ply,
}

impl MeshFormat {
    /// The mesh format a path names, if it names one.
    pub fn of(path: &Path) -> Option<MeshFormat> {
        match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
            "obj" => Some(MeshFormat::Obj),
            "glb" => Some(MeshFormat::Glb),
            "gltf" => Some(MeshFormat::Gltf),
            "ply" => Some(MeshFormat::Ply),
            _ => None,
        }
    }
}

/// Writes `scene` as a mesh to `path` (the format by its extension), atomically.
pub fn export(scene: &Scene, path: &Path, options: &MeshOptions) -> Result<MeshStats, FormatError> {
    export_watched(scene, path, options, &|_| true)
}

/// [`export`], telling `watch` the part done (0..1; the faces are 90 %, the file the rest);
/// when it says stop, nothing is written and [`FormatError::Cancelled`] comes back.
pub fn export_watched(
    scene: &Scene,
    path: &Path,
    options: &MeshOptions,
    watch: &dyn Fn(f64) -> bool,
) -> Result<MeshStats, FormatError> {
    let cancelled = || FormatError::Cancelled {
        path: path.display().to_string(),
    };
    let format = MeshFormat::of(path).ok_or_else(|| {
        FormatError::invalid(path, "a mesh is written as .obj, .glb, .gltf or .ply")
    })?;
    if !(options.voxel_size.is_finite() && options.voxel_size > 0.0) {
        return Err(FormatError::invalid(
            path,
            format!("voxel size {} must be positive", options.voxel_size),
        ));
    }
    let mesh = build_watched(scene, options, &|f| watch(0.9 * f)).ok_or_else(cancelled)?;
    if mesh.parts.iter().all(|p| p.quads.is_empty()) {
        return Err(FormatError::invalid(
            path,
            "the scene has no voxels to mesh",
        ));
    }
    let mesh = if options.keep_transforms && format != MeshFormat::Glb && format != MeshFormat::Gltf
    {
        // Only glTF has node transforms: the others get them applied.
        let flat = MeshOptions {
            keep_transforms: false,
            ..options.clone()
        };
        build_watched(scene, &flat, &|f| watch(0.9 * f)).ok_or_else(cancelled)?
    } else {
        mesh
    };
    if !watch(0.9) {
        return Err(cancelled());
    }
    match format {
        MeshFormat::Obj => obj::write(&mesh, path)?,
        MeshFormat::Glb => gltf::write(&mesh, path, true)?,
        MeshFormat::Gltf => gltf::write(&mesh, path, false)?,
        MeshFormat::Ply => ply::write(&mesh, path)?,
    }
    Ok(mesh.stats())
}

/// sRGB (0..=255) to linear (0..=1).
pub fn linear(c: u8) -> f64 {
    let s = f64::from(c) / 255.0;
    if s <= 0.04045 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}

/// Writes `bytes` to `path` atomically, naming the file in an error.
fn write_file(path: &Path, bytes: &[u8]) -> Result<(), FormatError> {
    crate::atomic::write_atomic(path, |w| w.write_all(bytes)).map_err(|e| FormatError::io(path, e))
}
