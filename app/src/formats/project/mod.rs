//! voxbrick project files (`.ron`): everything a scene is, as plain RON a person can read,
//! diff and edit, except the voxels, which are a compact base64 payload (see `payload`).
//!
//! ```text
//! (
//!     format_version: 1,
//!     grid_bricks: (64, 32, 64),
//!     camera: (position: (..), yaw_deg: .., pitch_deg: .., fov_y_deg: .., [projection: Orthographic(height: ..)]),
//!     sun: (enabled: true, position: (..), radius: .., colour: (..), intensity: .., ..),
//!     sky: Gradient(horizon: (..), zenith: (..)),
//!     settings: (samples_per_pixel: 1, max_bounces: 3, internal_resolution: (1024, 576), exposure: 0.0),
//!     materials: [(kind: Lambertian, param: 0, colour: 200), ..],
//!     colours: ["#56983a", ..],                     // 256 entries
//!     roughness: [..], ior: [..], strength: [..],   // 64 entries each
//!     voxels: (encoding: "vxb1-base64", bricks: .., solid_voxels: .., data: "VlhCMQ.."),
//! )
//! ```
//! Loading checks the version first (newer: a clear error; version 2, a scene of objects,
//! is read by `objects.rs`), then every field, then every brick; nothing is allocated beyond
//! what the file's length justifies, except the dense grid of the declared (supported) size.

mod objects;

use super::{FormatError, payload};
use crate::scene::Scene;
use base64::Engine;
use brickmap::{GridDims, Material, MaterialKind, MaterialTable, World, WorldConfig, terrain};
use render::{Camera, RenderSettings, SceneParams, Sky, Sun};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The version of a project of one grid, which `save` writes and `load` reads.
pub const FORMAT_VERSION: u32 = 1;
/// The version of a project of objects (`objects.rs`), the newest this program reads.
pub const OBJECTS_VERSION: u32 = 2;
const ENCODING: &str = "vxb1-base64";

#[derive(Deserialize)]
struct Probe {
    format_version: u32,
}

#[derive(Serialize, Deserialize)]
struct ProjectFile {
    format_version: u32,
    grid_bricks: (u32, u32, u32),
    camera: Camera,
    sun: Sun,
    sky: Sky,
    settings: RenderSettings,
    materials: Vec<MaterialRecord>,
    colours: Vec<String>,
    roughness: Vec<f32>,
    ior: Vec<f32>,
    strength: Vec<f32>,
    voxels: VoxelRecord,
}

#[derive(Serialize, Deserialize)]
struct MaterialRecord {
    kind: Kind,
    param: u8,
    colour: u8,
}

#[derive(Serialize, Deserialize, Clone, Copy)]
enum Kind {
    Lambertian,
    Metal,
    Dielectric,
    Emissive,
}

#[derive(Serialize, Deserialize)]
struct VoxelRecord {
    encoding: String,
    bricks: u64,
    solid_voxels: u64,
    data: String,
}

impl From<MaterialKind> for Kind {
    fn from(k: MaterialKind) -> Self {
        match k {
            MaterialKind::Lambertian => Kind::Lambertian,
            MaterialKind::Metal => Kind::Metal,
            MaterialKind::Dielectric => Kind::Dielectric,
            MaterialKind::Emissive => Kind::Emissive,
        }
    }
}

impl From<Kind> for MaterialKind {
    fn from(k: Kind) -> Self {
        match k {
            Kind::Lambertian => MaterialKind::Lambertian,
            Kind::Metal => MaterialKind::Metal,
            Kind::Dielectric => MaterialKind::Dielectric,
            Kind::Emissive => MaterialKind::Emissive,
        }
    }
}

/// The project text of a scene (version 2: its objects).
pub fn to_string(scene: &Scene) -> String {
    objects::to_string(scene)
}

/// The version 1 project text of a scene's composite (one grid, as voxbrick wrote before
/// objects; what older versions read).
pub fn grid_to_string(scene: &Scene) -> String {
    let view = scene.world.read();
    let data = payload::encode(&view);
    let voxels = VoxelRecord {
        encoding: ENCODING.into(),
        bricks: view.brick_count() + view.memory().full_cells,
        solid_voxels: view.solid_count(),
        data: base64_on_cores(&data),
    };
    drop(view);
    let mut fields = header(scene, FORMAT_VERSION);
    fields.push(("voxels", voxels.text()));
    layout(&fields)
}

impl VoxelRecord {
    /// The record in ron's compact form, as [`ron`] writes it, without ron's character by
    /// character escaping of the payload (base64 has nothing to escape): a large model's
    /// hundreds of megabytes written at memory speed.
    fn text(&self) -> String {
        debug_assert!(
            self.encoding
                .bytes()
                .all(|b| b.is_ascii_alphanumeric() || b == b'-')
        );
        let mut t = String::with_capacity(self.data.len() + 96);
        t.push_str("(encoding: \"");
        t.push_str(&self.encoding);
        t.push_str(&format!(
            "\", bricks: {}, solid_voxels: {}, data: \"",
            self.bricks, self.solid_voxels
        ));
        t.push_str(&self.data);
        t.push_str("\")");
        t
    }
}

/// Base64 (standard, padded) of `data`, in pieces of whole 3-byte groups on every core:
/// the same text as one encoding.
fn base64_on_cores(data: &[u8]) -> String {
    let engine = &base64::engine::general_purpose::STANDARD;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    if data.len() < 1 << 20 || threads < 2 {
        return engine.encode(data);
    }
    let piece = data.len().div_ceil(threads).div_ceil(3) * 3;
    let parts: Vec<String> = std::thread::scope(|s| {
        let handles: Vec<_> = data
            .chunks(piece)
            .map(|c| s.spawn(move || engine.encode(c)))
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("base64 threads do not panic"))
            .collect()
    });
    parts.concat()
}

/// A value in ron's compact form.
fn ron<T: Serialize>(v: &T) -> String {
    let compact = ron::ser::PrettyConfig::new()
        .compact_structs(true)
        .compact_arrays(true);
    ron::ser::to_string_pretty(v, compact).expect("project data always serializes")
}

/// A list, `per_line` items a line.
fn list<T: Serialize>(items: &[T], per_line: usize) -> String {
    let lines: Vec<String> = items
        .chunks(per_line)
        .map(|c| {
            format!(
                "        {},",
                c.iter().map(ron).collect::<Vec<_>>().join(", ")
            )
        })
        .collect();
    format!("[\n{}\n    ]", lines.join("\n"))
}

/// The fields every version shares: version, grid, camera, sun, sky, settings and the
/// material, colour and parameter tables.
fn header(scene: &Scene, version: u32) -> Vec<(&'static str, String)> {
    let table = scene.world.materials();
    let b = scene.world.dims().bricks();
    let materials: Vec<MaterialRecord> = (0..table.len())
        .map(|i| {
            let m = table.get(i as u8).expect("index within the table");
            MaterialRecord {
                kind: m.kind.into(),
                param: m.param,
                colour: m.colour,
            }
        })
        .collect();
    let colours: Vec<String> = (0..=255u8)
        .map(|i| {
            let [r, g, b] = table.colour(i);
            format!("#{r:02x}{g:02x}{b:02x}")
        })
        .collect();
    vec![
        ("format_version", ron(&version)),
        ("grid_bricks", ron(&(b.x, b.y, b.z))),
        ("camera", ron(&scene.params.camera)),
        ("sun", ron(&scene.params.sun)),
        ("sky", ron(&scene.params.sky)),
        ("settings", ron(&scene.params.settings)),
        ("materials", list(&materials, 1)),
        ("colours", list(&colours, 8)),
        ("roughness", list(&table.gpu().roughness, 16)),
        ("ior", list(&table.gpu().ior, 16)),
        ("strength", list(&table.gpu().strength, 16)),
    ]
}

/// Lays the file out for people and diffs: one line per field, per material, per eight
/// colours; every value in ron's compact form (so the result is plain RON).
fn layout(fields: &[(&str, String)]) -> String {
    let body: Vec<String> = fields
        .iter()
        .map(|(k, v)| format!("    {k}: {v},"))
        .collect();
    format!("(\n{}\n)\n", body.join("\n"))
}

/// Saves a scene atomically.
pub fn save(scene: &Scene, path: &Path) -> Result<(), FormatError> {
    let text = to_string(scene);
    crate::atomic::write_atomic(path, |w| w.write_all(text.as_bytes()))
        .map_err(|e| FormatError::io(path, e))
}

/// Loads a project file.
pub fn load(path: &Path, workers: usize) -> Result<Scene, FormatError> {
    let text = std::fs::read(path).map_err(|e| FormatError::io(path, e))?;
    from_bytes(&text, path, workers)
}

/// Parses project text (`path` only names it in errors): version 2 as written, version 1
/// as one object.
pub fn from_bytes(text: &[u8], path: &Path, workers: usize) -> Result<Scene, FormatError> {
    let invalid = |m: String| FormatError::invalid(path, m);
    let text = std::str::from_utf8(text).map_err(|e| invalid(format!("not UTF-8 text: {e}")))?;
    match version(text, path)? {
        FORMAT_VERSION => grid_from_str(text, path, workers),
        _ => objects::from_str(text, path, workers),
    }
}

/// A version 1 project: one grid, which becomes one object.
fn grid_from_str(text: &str, path: &Path, workers: usize) -> Result<Scene, FormatError> {
    let invalid = |m: String| FormatError::invalid(path, m);
    let file: ProjectFile = ron::from_str(text).map_err(|e| invalid(format!("{e}")))?;
    let (params, dims, table) = header_of!(file).read(path)?;
    let bricks = file.voxels.bricks(&dims, table.len(), path)?;
    let world = World::new(dims, WorldConfig::with_workers(workers))
        .map_err(|e| FormatError::world(path, e))?;
    world
        .replace_materials(table)
        .map_err(|e| FormatError::world(path, e))?;
    world
        .apply_unrecorded(terrain::set_bricks(bricks))
        .map_err(|e| FormatError::world(path, e))?;
    let solid = world.read().solid_count();
    if solid != file.voxels.solid_voxels {
        return Err(invalid(format!(
            "voxels hold {solid} solid voxels, the header says {}",
            file.voxels.solid_voxels
        )));
    }
    world.take_dirty();
    Ok(Scene::new(world, params))
}

/// The project version a text declares: refused when newer than this program reads, or one
/// that never existed.
fn version(text: &str, path: &Path) -> Result<u32, FormatError> {
    let invalid = |m: String| FormatError::invalid(path, m);
    // The probe's own name never reaches the user: the file is not a project, and where.
    let probe: Probe = ron::from_str(text).map_err(|e| {
        invalid(format!(
            "not a voxbrick project (a project begins with `(format_version: {FORMAT_VERSION},`; \
             this file does not, line {} column {})",
            e.span.start.line, e.span.start.col
        ))
    })?;
    match probe.format_version {
        v if v > OBJECTS_VERSION => Err(FormatError::NewerVersion {
            path: path.display().to_string(),
            found: v,
            known: OBJECTS_VERSION,
        }),
        v @ (FORMAT_VERSION | OBJECTS_VERSION) => Ok(v),
        v => Err(invalid(format!(
            "format version {v} never existed (versions start at 1)"
        ))),
    }
}

/// The shared fields of a file struct of any version, as a [`Header`].
macro_rules! header_of {
    ($file:expr) => {
        Header {
            grid_bricks: $file.grid_bricks,
            camera: $file.camera,
            sun: $file.sun,
            sky: $file.sky,
            settings: $file.settings,
            materials: &$file.materials,
            colours: &$file.colours,
            roughness: &$file.roughness,
            ior: &$file.ior,
            strength: &$file.strength,
        }
    };
}
use header_of;

impl VoxelRecord {
    /// The record's bricks over a grid of `dims` with a table of `materials` entries: the
    /// encoding, the base64, the payload and the brick count checked.
    fn bricks(
        &self,
        dims: &GridDims,
        materials: usize,
        path: &Path,
    ) -> Result<Vec<(glam::UVec3, brickmap::Mask, brickmap::PriorMaterials)>, FormatError> {
        let invalid = |m: String| FormatError::invalid(path, m);
        if self.encoding != ENCODING {
            return Err(invalid(format!(
                "unknown voxel encoding {:?} (expected {ENCODING:?})",
                self.encoding
            )));
        }
        let data = base64::engine::general_purpose::STANDARD
            .decode(self.data.as_bytes())
            .map_err(|e| invalid(format!("voxel payload is not base64: {e}")))?;
        let bricks =
            payload::decode(&data, dims, materials).map_err(|e| FormatError::payload(path, e))?;
        if bricks.len() as u64 != self.bricks {
            return Err(invalid(format!(
                "voxel payload holds {} bricks, the header says {}",
                bricks.len(),
                self.bricks
            )));
        }
        Ok(bricks)
    }
}

/// The fields every version shares, as read, before they are checked.
struct Header<'a> {
    grid_bricks: (u32, u32, u32),
    camera: Camera,
    sun: Sun,
    sky: Sky,
    settings: RenderSettings,
    materials: &'a [MaterialRecord],
    colours: &'a [String],
    roughness: &'a [f32],
    ior: &'a [f32],
    strength: &'a [f32],
}

impl Header<'_> {
    /// The scene parameters, the grid and the material table, each checked.
    fn read(self, path: &Path) -> Result<(SceneParams, GridDims, MaterialTable), FormatError> {
        let params = SceneParams {
            camera: self.camera,
            sun: self.sun,
            sky: self.sky,
            settings: self.settings,
        };
        params
            .validate()
            .map_err(|e| FormatError::invalid(path, e.to_string()))?;
        let (x, y, z) = self.grid_bricks;
        let dims = GridDims::new(x, y, z).map_err(|e| FormatError::world(path, e))?;
        let table = material_table(
            path,
            self.materials,
            self.colours,
            self.roughness,
            self.ior,
            self.strength,
        )?;
        Ok((params, dims, table))
    }
}

/// The scene's material table from the file's records; an error says which entry is wrong.
fn material_table(
    path: &Path,
    materials: &[MaterialRecord],
    colours: &[String],
    roughness: &[f32],
    ior: &[f32],
    strength: &[f32],
) -> Result<MaterialTable, FormatError> {
    let invalid = |m: String| FormatError::invalid(path, m);
    if materials.is_empty() || materials.len() > 256 {
        return Err(invalid(format!(
            "{} materials: a scene has 1 to 256",
            materials.len()
        )));
    }
    if colours.len() != 256 {
        return Err(invalid(format!(
            "{} colours: the colour table has exactly 256",
            colours.len()
        )));
    }
    for (name, t) in [
        ("roughness", roughness),
        ("ior", ior),
        ("strength", strength),
    ] {
        if t.len() != brickmap::material::PARAMS {
            return Err(invalid(format!(
                "{} {name} values: the table has exactly 64",
                t.len()
            )));
        }
    }
    let mut table = MaterialTable::default();
    for (i, c) in colours.iter().enumerate() {
        table.set_colour(
            i as u8,
            parse_colour(c).ok_or_else(|| invalid(format!("colour {i} {c:?} is not #rrggbb")))?,
        );
    }
    for (kind, values) in [
        (MaterialKind::Metal, roughness),
        (MaterialKind::Dielectric, ior),
        (MaterialKind::Emissive, strength),
    ] {
        for (i, v) in values.iter().enumerate() {
            table
                .set_param(kind, i as u8, *v)
                .map_err(|e| invalid(format!("{kind:?} parameter {i}: {e}")))?;
        }
    }
    for (i, m) in materials.iter().enumerate() {
        let m = Material {
            kind: m.kind.into(),
            param: m.param,
            colour: m.colour,
        };
        let r = if i == 0 {
            table.set(0, m).map(|_| 0)
        } else {
            table.push(m)
        };
        r.map_err(|e| invalid(format!("material {i}: {e}")))?;
    }
    Ok(table)
}

fn parse_colour(s: &str) -> Option<[u8; 3]> {
    let hex = s
        .strip_prefix('#')
        .filter(|h| h.len() == 6 && h.is_ascii())?;
    let c = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).ok();
    Some([c(0)?, c(2)?, c(4)?])
}

#[cfg(test)]
mod text_tests {
    use super::*;

    #[test]
    fn a_voxel_record_reads_as_ron_writes_it_and_base64_in_pieces_is_one_encoding() {
        let data: Vec<u8> = (0..(3 << 20) + 7)
            .map(|i| (i * 7 + i / 255) as u8)
            .collect();
        let b64 = base64_on_cores(&data);
        assert_eq!(b64, base64::engine::general_purpose::STANDARD.encode(&data));
        let r = VoxelRecord {
            encoding: ENCODING.into(),
            bricks: 12,
            solid_voxels: 3456,
            data: b64[..4000].to_string(),
        };
        assert_eq!(r.text(), ron(&r));
    }
}
