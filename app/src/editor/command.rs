//! Everything the editor can do to a document, as serializable commands (scripts and the
//! recorder use the same form). `apply` executes one and returns how to undo it: voxel
//! commands keep the sparse inverses the world returns, table commands the previous table
//! (about 2 KB), property commands the previous value. Never a snapshot of the world.

use crate::scene::Scene;
use anyhow::{Context, Result, bail, ensure};
use brickmap::terrain::{NoiseKind, NoiseTerrain};
use brickmap::{
    EditInverse, EditOp, Material, MaterialKind, MaterialTable, Mode, Shape, VoxelEdit, VoxelOp,
};
use glam::{DVec3, IVec3};
use render::{Camera, RenderSettings, Sky, Sun};
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;

/// What a brush does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum BrushMode {
    /// Add solid voxels with the material.
    Attach,
    /// Remove voxels.
    Erase,
    /// Repaint solid voxels, keeping the shape.
    Paint,
}

/// The brush's shape at each stroke point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum BrushShape {
    /// The voxel under the point.
    Voxel,
    /// A ball of radius `size`.
    Sphere,
    /// A cube of half-size `size` (edge 2·size + 1 voxels) centred on the point's voxel.
    Cube,
    /// An upright cylinder of radius and half-height `size`.
    Cylinder,
    /// Capsules of radius `size` along the stroke's points.
    Line,
    /// The box spanned by the stroke's first and last points.
    Box,
}

/// Mirror symmetry about planes through `centre`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Mirror {
    /// Mirror across x = centre.x.
    pub x: bool,
    /// Mirror across y = centre.y.
    pub y: bool,
    /// Mirror across z = centre.z.
    pub z: bool,
    /// The point the mirror planes go through.
    pub centre: DVec3,
}

/// A brush stroke: one undo step however many points it has.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stroke {
    /// Attach, erase or paint.
    pub mode: BrushMode,
    /// Shape at each point.
    pub shape: BrushShape,
    /// Radius or half-size, > 0 (ignored for Voxel and Box).
    pub size: f64,
    /// Material for attach and paint.
    pub material: u8,
    /// Symmetry.
    #[serde(default)]
    pub mirror: Mirror,
    /// Points, in voxel coordinates.
    pub points: Vec<DVec3>,
}

/// Terrain parameters a command carries (materials are added by the command).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TerrainSpec {
    /// Seed.
    pub seed: u32,
    /// Wavelength of the first octave in voxels.
    pub scale: f64,
    /// Octaves.
    pub octaves: u32,
    /// Surface height range.
    pub height_range: (u32, u32),
    /// Water level (0: none).
    pub water_level: u32,
}

/// Every change a document can undergo.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Command {
    /// A brush stroke.
    Stroke(Stroke),
    /// Repaint the connected surface of same-material voxels containing `start`.
    FloodFill {
        /// A solid voxel of the surface.
        start: IVec3,
        /// The new material.
        material: u8,
    },
    /// Append a material.
    AddMaterial(MaterialSpec),
    /// Replace a material.
    SetMaterial {
        /// Table index.
        index: u8,
        /// New value.
        material: MaterialSpec,
    },
    /// Replace a colour of the colour table.
    SetColour {
        /// Colour index.
        index: u8,
        /// sRGB.
        rgb: [u8; 3],
    },
    /// Set a parameter-table value (roughness, IOR, strength).
    SetParam {
        /// Which table.
        kind: KindSpec,
        /// Index 0..64.
        index: u8,
        /// Value.
        value: f32,
    },
    /// Replace the sun.
    SetSun(Sun),
    /// Replace the sky.
    SetSky(Sky),
    /// Replace the camera.
    SetCamera(Camera),
    /// Replace the render settings.
    SetSettings(RenderSettings),
    /// Replace the whole grid by noise terrain with water (adds its materials).
    GenerateTerrain(TerrainSpec),
    /// Import a .vox file at an offset (path relative to the working folder).
    ImportVox {
        /// The file.
        path: String,
        /// Offset added after the shift into the grid.
        offset: IVec3,
    },
    /// Remove every voxel.
    Clear,
}

/// A material in commands and scripts.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MaterialSpec {
    /// Type.
    pub kind: KindSpec,
    /// Parameter-table index.
    pub param: u8,
    /// Colour index.
    pub colour: u8,
}

/// Material types in commands and scripts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum KindSpec {
    /// Lambertian.
    Lambertian,
    /// Metal.
    Metal,
    /// Dielectric.
    Dielectric,
    /// Emissive.
    Emissive,
}

impl From<KindSpec> for MaterialKind {
    fn from(k: KindSpec) -> Self {
        match k {
            KindSpec::Lambertian => MaterialKind::Lambertian,
            KindSpec::Metal => MaterialKind::Metal,
            KindSpec::Dielectric => MaterialKind::Dielectric,
            KindSpec::Emissive => MaterialKind::Emissive,
        }
    }
}

impl From<MaterialSpec> for Material {
    fn from(m: MaterialSpec) -> Self {
        Material {
            kind: m.kind.into(),
            param: m.param,
            colour: m.colour,
        }
    }
}

/// How to undo a command.
#[derive(Debug)]
pub enum Inverse {
    /// Voxel edits to restore in reverse order, then (if any) the material table.
    Voxels(Vec<EditInverse>, Option<Box<MaterialTable>>),
    /// The previous material table.
    Table(Box<MaterialTable>),
    /// The previous sun.
    Sun(Sun),
    /// The previous sky.
    Sky(Sky),
    /// The previous camera.
    Camera(Camera),
    /// The previous settings.
    Settings(RenderSettings),
}

impl Inverse {
    /// Heap and inline bytes this inverse holds (what the history pays for it).
    pub fn bytes(&self) -> usize {
        let table = std::mem::size_of::<MaterialTable>();
        std::mem::size_of::<Self>()
            + match self {
                Inverse::Voxels(v, t) => {
                    v.iter().map(|i| i.heap_bytes()).sum::<usize>()
                        + t.as_ref().map_or(0, |_| table)
                }
                Inverse::Table(_) => table,
                _ => 0,
            }
    }

    /// Applies the inverse, returning the inverse of that (redo after undo, and back).
    pub fn apply(self, scene: &mut Scene) -> Result<Inverse> {
        Ok(match self {
            Inverse::Voxels(list, table) => {
                // A table that grows goes in before the voxels that use it; one that shrinks
                // after the voxels that used the dropped entries are gone.
                let grows = table
                    .as_ref()
                    .is_some_and(|t| t.len() >= scene.world.materials().len());
                let mut old = None;
                if grows && let Some(t) = table.as_ref() {
                    old = Some(Box::new(scene.world.replace_materials((**t).clone())?));
                }
                let mut back = Vec::with_capacity(list.len());
                for inv in list.into_iter().rev() {
                    back.push(scene.world.apply(EditOp::Restore(inv))?.inverse);
                }
                if !grows && let Some(t) = table {
                    old = Some(Box::new(scene.world.replace_materials(*t)?));
                }
                Inverse::Voxels(back, old)
            }
            Inverse::Table(t) => Inverse::Table(Box::new(scene.world.replace_materials(*t)?)),
            Inverse::Sun(v) => Inverse::Sun(std::mem::replace(&mut scene.params.sun, v)),
            Inverse::Sky(v) => Inverse::Sky(std::mem::replace(&mut scene.params.sky, v)),
            Inverse::Camera(v) => Inverse::Camera(std::mem::replace(&mut scene.params.camera, v)),
            Inverse::Settings(v) => {
                Inverse::Settings(std::mem::replace(&mut scene.params.settings, v))
            }
        })
    }
}

impl Command {
    /// A label for the history list.
    pub fn label(&self) -> String {
        match self {
            Command::Stroke(s) => format!(
                "{:?} {:?} stroke ({} points)",
                s.mode,
                s.shape,
                s.points.len()
            ),
            Command::FloodFill { start, material } => {
                format!("Fill from {start} with material {material}")
            }
            Command::AddMaterial(_) => "Add material".into(),
            Command::SetMaterial { index, .. } => format!("Edit material {index}"),
            Command::SetColour { index, .. } => format!("Edit colour {index}"),
            Command::SetParam { kind, index, .. } => format!("Edit {kind:?} parameter {index}"),
            Command::SetSun(_) => "Edit sun".into(),
            Command::SetSky(_) => "Edit sky".into(),
            Command::SetCamera(_) => "Move camera".into(),
            Command::SetSettings(_) => "Edit render settings".into(),
            Command::GenerateTerrain(t) => format!("Generate terrain (seed {})", t.seed),
            Command::ImportVox { path, .. } => format!("Import {path}"),
            Command::Clear => "Clear".into(),
        }
    }

    /// Commands with equal keys that follow each other merge into one step (dragging a slider).
    pub fn coalesce_key(&self) -> Option<String> {
        match self {
            Command::SetColour { index, .. } => Some(format!("colour {index}")),
            Command::SetParam { kind, index, .. } => Some(format!("param {kind:?} {index}")),
            Command::SetMaterial { index, .. } => Some(format!("material {index}")),
            Command::SetSun(_) => Some("sun".into()),
            Command::SetSky(_) => Some("sky".into()),
            Command::SetCamera(_) => Some("camera".into()),
            Command::SetSettings(_) => Some("settings".into()),
            _ => None,
        }
    }

    /// Executes the command. On error the scene is as it was.
    pub fn apply(&self, scene: &mut Scene, folder: &std::path::Path) -> Result<Applied> {
        let world = &scene.world;
        let unchanged = |inverse| Applied {
            inverse,
            changed_voxels: 0,
        };
        Ok(match self {
            Command::Stroke(s) => apply_all(scene, stroke_edits(s)?)?,
            Command::FloodFill { start, material } => {
                world.materials().check(*material as u32)?;
                let edits = flood_fill(scene, *start, *material)?;
                apply_all(scene, vec![EditOp::Voxels(edits)])?
            }
            Command::Clear => {
                let max = world.dims().voxels() - 1;
                let clear = EditOp::Shape {
                    shape: Shape::Box {
                        min: IVec3::ZERO,
                        max,
                    },
                    mode: Mode::Remove,
                };
                apply_all(scene, vec![clear])?
            }
            Command::AddMaterial(m) => {
                with_table(scene, |w| w.push_material((*m).into()).map(|_| ()))?
            }
            Command::SetMaterial { index, material } => with_table(scene, |w| {
                w.set_material(*index, (*material).into()).map(|_| ())
            })?,
            Command::SetColour { index, rgb } => with_table(scene, |w| {
                w.set_colour(*index, *rgb);
                Ok(())
            })?,
            Command::SetParam { kind, index, value } => with_table(scene, |w| {
                w.set_param((*kind).into(), *index, *value).map(|_| ())
            })?,
            Command::SetSun(v) => {
                v.validate()?;
                unchanged(Inverse::Sun(std::mem::replace(
                    &mut scene.params.sun,
                    v.clone(),
                )))
            }
            Command::SetSky(v) => {
                v.validate()?;
                unchanged(Inverse::Sky(std::mem::replace(
                    &mut scene.params.sky,
                    v.clone(),
                )))
            }
            Command::SetCamera(v) => {
                v.validate()?;
                unchanged(Inverse::Camera(std::mem::replace(
                    &mut scene.params.camera,
                    v.clone(),
                )))
            }
            Command::SetSettings(v) => {
                v.validate()?;
                unchanged(Inverse::Settings(std::mem::replace(
                    &mut scene.params.settings,
                    v.clone(),
                )))
            }
            Command::GenerateTerrain(t) => {
                let before = world.materials().clone();
                let result = (|| {
                    let materials = crate::scene::terrain_materials(world)?;
                    let mut params =
                        crate::scene::thesis_terrain(materials, world.dims().voxels().y as u32);
                    (params.seed, params.noise, params.scale, params.octaves) =
                        (t.seed, NoiseKind::Perlin, t.scale, t.octaves);
                    (params.height_range, params.water_level) = (t.height_range, t.water_level);
                    let edit = NoiseTerrain::new(params, world.dims())?.edit();
                    Ok::<_, anyhow::Error>(world.apply(edit)?)
                })();
                match result {
                    Ok(out) => Applied {
                        inverse: Inverse::Voxels(vec![out.inverse], Some(Box::new(before))),
                        changed_voxels: out.changed_voxels,
                    },
                    Err(e) => {
                        world.replace_materials(before)?;
                        return Err(e);
                    }
                }
            }
            Command::ImportVox { path, offset } => {
                let file = folder.join(path);
                let bytes =
                    std::fs::read(&file).with_context(|| format!("reading {}", file.display()))?;
                let before = world.materials().clone();
                let options = crate::formats::vox::ImportOptions {
                    offset: *offset,
                    ..Default::default()
                };
                match crate::formats::vox::import_into(world, &bytes, &options, None) {
                    Ok((report, inv)) => Applied {
                        inverse: Inverse::Voxels(vec![inv], Some(Box::new(before))),
                        changed_voxels: report.voxels,
                    },
                    Err(e) => {
                        world.replace_materials(before)?;
                        bail!("{}: {e}", file.display());
                    }
                }
            }
        })
    }
}

/// An executed command: how to undo it, and how many voxels it changed (for an import, how
/// many it wrote).
#[derive(Debug)]
pub struct Applied {
    /// The undo.
    pub inverse: Inverse,
    /// Voxels whose occupancy or material changed.
    pub changed_voxels: u64,
}

/// Runs a table edit, keeping the previous table as the inverse (and putting it back on error).
fn with_table(
    scene: &Scene,
    edit: impl FnOnce(&brickmap::World) -> brickmap::Result<()>,
) -> Result<Applied> {
    let before = scene.world.materials().clone();
    if let Err(e) = edit(&scene.world) {
        scene.world.replace_materials(before)?;
        return Err(e.into());
    }
    Ok(Applied {
        inverse: Inverse::Table(Box::new(before)),
        changed_voxels: 0,
    })
}

/// Applies edits in order; if one fails, the ones applied are undone and the error returned.
fn apply_all(scene: &Scene, edits: Vec<EditOp>) -> Result<Applied> {
    let mut done: Vec<EditInverse> = Vec::with_capacity(edits.len());
    let mut changed = 0;
    for edit in edits {
        match scene.world.apply(edit) {
            Ok(out) => {
                changed += out.changed_voxels;
                done.push(out.inverse);
            }
            Err(e) => {
                for inv in done.into_iter().rev() {
                    scene.world.apply(EditOp::Restore(inv))?;
                }
                return Err(e.into());
            }
        }
    }
    Ok(Applied {
        inverse: Inverse::Voxels(done, None),
        changed_voxels: changed,
    })
}

/// The world edits of a stroke, mirror images included, validated before any is applied.
pub fn stroke_edits(s: &Stroke) -> Result<Vec<EditOp>> {
    ensure!(!s.points.is_empty(), "a stroke needs at least one point");
    ensure!(
        s.points.iter().all(|p| p.is_finite()),
        "stroke points must be finite"
    );
    let sized = !matches!(s.shape, BrushShape::Voxel | BrushShape::Box);
    ensure!(
        !sized || (s.size.is_finite() && s.size > 0.0),
        "brush size {} must be positive",
        s.size
    );
    let mode = match s.mode {
        BrushMode::Attach => Mode::Add(s.material),
        BrushMode::Erase => Mode::Remove,
        BrushMode::Paint => Mode::Paint(s.material),
    };
    // Every combination of reflections across the enabled mirror planes (up to 8 images).
    let m = &s.mirror;
    let axes: Vec<usize> = [(0, m.x), (1, m.y), (2, m.z)]
        .into_iter()
        .filter(|a| a.1)
        .map(|a| a.0)
        .collect();
    let reflect = |p: DVec3, combo: usize| {
        let mut q = p;
        for (k, &axis) in axes.iter().enumerate() {
            if combo >> k & 1 == 1 {
                q[axis] = 2.0 * m.centre[axis] - q[axis];
            }
        }
        q
    };
    let mut edits = Vec::new();
    for combo in 0..1usize << axes.len() {
        let pts: Vec<DVec3> = s.points.iter().map(|p| reflect(*p, combo)).collect();
        let shapes: Vec<Shape> = match s.shape {
            BrushShape::Line => vec![Shape::Line {
                points: pts,
                radius: s.size,
            }],
            BrushShape::Box => {
                let (a, b) = (
                    pts[0].floor().as_ivec3(),
                    pts[pts.len() - 1].floor().as_ivec3(),
                );
                vec![Shape::Box {
                    min: a.min(b),
                    max: a.max(b),
                }]
            }
            BrushShape::Voxel => pts
                .iter()
                .map(|p| Shape::Voxel(p.floor().as_ivec3()))
                .collect(),
            BrushShape::Sphere => pts
                .iter()
                .map(|p| Shape::Sphere {
                    centre: *p,
                    radius: s.size,
                })
                .collect(),
            BrushShape::Cube => {
                let h = s.size.round().max(0.0) as i32;
                pts.iter()
                    .map(|p| {
                        let c = p.floor().as_ivec3();
                        Shape::Box {
                            min: c - h,
                            max: c + h,
                        }
                    })
                    .collect()
            }
            BrushShape::Cylinder => pts
                .iter()
                .map(|p| Shape::Cylinder {
                    a: *p - DVec3::Y * s.size,
                    b: *p + DVec3::Y * s.size,
                    radius: s.size,
                })
                .collect(),
        };
        for shape in shapes {
            shape.validate()?;
            edits.push(EditOp::Shape { shape, mode });
        }
    }
    Ok(edits)
}

/// Paint edits for the connected (6-neighbour) surface of voxels sharing `start`'s material;
/// a voxel is on the surface when a face neighbour is empty or outside the grid.
fn flood_fill(scene: &Scene, start: IVec3, material: u8) -> Result<Vec<VoxelEdit>> {
    const LIMIT: usize = 1 << 24;
    let view = scene.world.read();
    let dims = view.dims();
    let target = view
        .voxel(start)?
        .with_context(|| format!("flood fill starts at {start}, which is empty"))?;
    let faces = [
        IVec3::X,
        IVec3::NEG_X,
        IVec3::Y,
        IVec3::NEG_Y,
        IVec3::Z,
        IVec3::NEG_Z,
    ];
    let on_surface = |v: IVec3| {
        faces
            .iter()
            .any(|f| !dims.contains_voxel(v + *f) || view.voxel(v + *f).ok().flatten().is_none())
    };
    ensure!(
        on_surface(start),
        "flood fill starts at {start}, which is not on a surface"
    );
    let mut seen = std::collections::HashSet::from([start]);
    let mut queue = VecDeque::from([start]);
    let mut edits = Vec::new();
    while let Some(v) = queue.pop_front() {
        edits.push(VoxelEdit {
            pos: v,
            op: VoxelOp::Paint(material),
        });
        ensure!(
            edits.len() <= LIMIT,
            "flood fill reaches more than {LIMIT} voxels"
        );
        for f in faces {
            let n = v + f;
            if dims.contains_voxel(n)
                && !seen.contains(&n)
                && view.voxel(n)? == Some(target)
                && on_surface(n)
            {
                seen.insert(n);
                queue.push_back(n);
            }
        }
    }
    Ok(edits)
}
