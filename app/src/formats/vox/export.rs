//! `.vox` out: the world as ≤ 256³ models under one group, the palette (at most 255 slots:
//! `dot_vox` adds the file's 1 with a `u8` add) and MATL chunks that invert the import.

use super::*;

/// The `.vox` data of a scene: ≤ 256³ models under one group, a palette slot per used
/// material (at most 255), MATL for each.
pub fn export_data(world: &World) -> Result<DotVoxData, VoxError> {
    let view = world.read();
    let table = view.materials();
    let mut slots = Slots::default();
    let mut chunks: BTreeMap<(i32, i32, i32), Vec<Voxel>> = BTreeMap::new();
    let mut failure = None;
    view.for_each_brick(|b, mask, mats| {
        let base = b.as_ivec3() * 8;
        for (k, bit) in mask.ones().enumerate() {
            let m = match mats {
                BrickMaterials::Uniform(m) => m,
                BrickMaterials::PerVoxel(v) => v[k],
            };
            let i = match slots.slot(m) {
                Ok(i) => i,
                Err(e) => {
                    failure.get_or_insert(e);
                    return;
                }
            };
            let p = base + IVec3::new((bit % 8) as i32, (bit / 8 % 8) as i32, (bit / 64) as i32);
            let vox = IVec3::new(p.x, -p.z - 1, p.y);
            let chunk = (
                vox.x.div_euclid(256),
                vox.y.div_euclid(256),
                vox.z.div_euclid(256),
            );
            let local = vox - IVec3::new(chunk.0, chunk.1, chunk.2) * 256;
            chunks.entry(chunk).or_default().push(Voxel {
                x: local.x as u8,
                y: local.y as u8,
                z: local.z as u8,
                i,
            });
        }
    });
    if let Some(f) = failure {
        return Err(f);
    }
    let (palette, materials) = slots.palette_and_materials(table)?;
    // Scene graph: 0 root transform → 1 group → (transform → shape) per model.
    let mut scenes = vec![
        SceneNode::Transform {
            attributes: Default::default(),
            frames: vec![dot_vox::Frame::new(Default::default())],
            child: 1,
            layer_id: u32::MAX,
        },
        SceneNode::Group {
            attributes: Default::default(),
            children: Vec::new(),
        },
    ];
    let mut models = Vec::new();
    for ((cx, cy, cz), voxels) in chunks {
        let size = voxels.iter().fold(IVec3::ONE, |s, v| {
            s.max(IVec3::new(v.x as i32, v.y as i32, v.z as i32) + 1)
        });
        let t = IVec3::new(cx, cy, cz) * 256 + size / 2;
        let transform_id = scenes.len() as u32;
        let mut frame = dot_vox::Dict::new();
        frame.insert("_t".into(), format!("{} {} {}", t.x, t.y, t.z));
        scenes.push(SceneNode::Transform {
            attributes: Default::default(),
            frames: vec![dot_vox::Frame::new(frame)],
            child: transform_id + 1,
            layer_id: 0,
        });
        scenes.push(SceneNode::Shape {
            attributes: Default::default(),
            models: vec![dot_vox::ShapeModel {
                model_id: models.len() as u32,
                attributes: Default::default(),
            }],
        });
        if let SceneNode::Group { children, .. } = &mut scenes[1] {
            children.push(transform_id);
        }
        models.push(vox_model(size, voxels));
    }
    let mut layer = dot_vox::Dict::new();
    layer.insert("_name".into(), "voxbrick".into());
    let layers = vec![dot_vox::Layer { attributes: layer }];
    Ok(vox_data(models, (palette, materials), scenes, layers))
}

/// A `.vox` file's data (version 150, the default index map) of its parts.
pub(super) fn vox_data(
    models: Vec<Model>,
    (palette, materials): (Vec<Color>, Vec<dot_vox::Material>),
    scenes: Vec<SceneNode>,
    layers: Vec<dot_vox::Layer>,
) -> DotVoxData {
    DotVoxData {
        version: 150,
        index_map: dot_vox::DEFAULT_INDEX_MAP.to_vec(),
        models,
        palette,
        materials,
        scenes,
        layers,
    }
}

/// A `.vox` model of a size (in the file's axes, each side 1..=256) and its voxels.
pub(super) fn vox_model(size: IVec3, voxels: Vec<Voxel>) -> Model {
    Model {
        size: Size {
            x: size.x as u32,
            y: size.y as u32,
            z: size.z as u32,
        },
        voxels,
    }
}

/// Palette slots handed to materials as voxels are written (at most 255), and the palette
/// and MATL chunks they make.
#[derive(Default)]
pub(super) struct Slots {
    used: Vec<u8>,
    slot_of: HashMap<u8, u8>,
}

impl Slots {
    /// The palette slot (0-based) of material `m`, given on first use.
    pub(super) fn slot(&mut self, m: u8) -> Result<u8, VoxError> {
        if let Some(s) = self.slot_of.get(&m) {
            return Ok(*s);
        }
        if self.used.len() == 255 {
            return Err(VoxError::TooManyMaterials);
        }
        let s = self.used.len() as u8;
        self.used.push(m);
        self.slot_of.insert(m, s);
        Ok(s)
    }

    /// The palette (the default one with the used slots overwritten) and a MATL per slot
    /// that inverts the import.
    pub(super) fn palette_and_materials(
        &self,
        table: &brickmap::MaterialTable,
    ) -> Result<(Vec<Color>, Vec<dot_vox::Material>), VoxError> {
        let mut palette = dot_vox::DEFAULT_PALETTE.to_vec();
        let mut materials = Vec::new();
        for (slot, &m) in self.used.iter().enumerate() {
            let mat = table.get(m)?;
            let [r, g, b] = table.colour(mat.colour);
            palette[slot] = Color { r, g, b, a: 255 };
            let param = table.param(mat.kind, mat.param)?;
            let mut props = dot_vox::Dict::new();
            let mut set = |k: &str, v: String| {
                props.insert(k.to_string(), v);
            };
            match mat.kind {
                MaterialKind::Lambertian => set("_type", "_diffuse".into()),
                MaterialKind::Metal => {
                    set("_type", "_metal".into());
                    set("_metal", "1".into());
                    set("_rough", format!("{param}"));
                }
                MaterialKind::Dielectric => {
                    set("_type", "_glass".into());
                    set("_trans", "1".into());
                    set("_ior", format!("{}", param - 1.0));
                    set("_ri", format!("{param}"));
                }
                MaterialKind::Emissive => {
                    set("_type", "_emit".into());
                    let emit = param.min(1.0);
                    let flux = if param > 1.0 { param.log2() } else { 0.0 };
                    set("_emit", format!("{emit}"));
                    set("_flux", format!("{flux}"));
                }
            }
            materials.push(dot_vox::Material {
                id: slot as u32 + 1,
                properties: props,
            });
        }
        Ok((palette, materials))
    }
}

/// Exports a scene's objects to a `.vox` file (its tree, layers and shared models),
/// atomically.
pub fn export_file(scene: &Scene, path: &Path) -> Result<ExportReport, FormatError> {
    let table = scene.world.materials().clone();
    super::objects::export_objects(&scene.objects(), &table, path)
}

/// Writes `.vox` data to a file, atomically, and says what it wrote.
pub(super) fn write_data(data: &DotVoxData, path: &Path) -> Result<ExportReport, FormatError> {
    let mut bytes = Vec::new();
    data.write_vox(&mut bytes)
        .map_err(|e| FormatError::io(path, e))?;
    crate::atomic::write_atomic(path, |w| w.write_all(&bytes))
        .map_err(|e| FormatError::io(path, e))?;
    Ok(ExportReport {
        models: data.models.len(),
        voxels: data.models.iter().map(|m| m.voxels.len() as u64).sum(),
        materials: data.materials.len(),
        bytes: bytes.len() as u64,
    })
}
