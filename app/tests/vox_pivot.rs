//! MagicaVoxel's pivot rule, pinned independently of the importer: a voxel v of a model of
//! size s under rotation R and translation t lands in the cell ⌊R·(v + ½ − ⌊s/2⌋) + t⌋
//! (opengametools' "explanation of model pivots"; vengi floors the same transformed centre).
//! Expected cells are computed here in f64 straight from that formula, for hand-worked
//! cases, every one of the 48 rotations on models of sizes 1–5 per axis, nested group
//! transforms, and the round trip import → export → import of a rotated multi-model scene.

mod common;

use app::formats::vox;
use dot_vox::*;
use glam::{DVec3, IVec3};
use std::collections::BTreeSet;
use std::path::Path;

/// The signed permutation a valid rotation byte encodes, as rows (bits 0–1: column of row 0,
/// bits 2–3: column of row 1, bits 4–6: signs of rows 0–2), written out here on its own.
fn rows_of(byte: u8) -> Option<[[f64; 3]; 3]> {
    let (c0, c1) = ((byte & 3) as usize, ((byte >> 2) & 3) as usize);
    if c0 > 2 || c1 > 2 || c0 == c1 || byte >> 7 != 0 {
        return None;
    }
    let c2 = 3 - c0 - c1;
    let mut m = [[0.0; 3]; 3];
    for (row, col) in [(0, c0), (1, c1), (2, c2)] {
        m[row][col] = if (byte >> (4 + row)) & 1 == 1 {
            -1.0
        } else {
            1.0
        };
    }
    Some(m)
}

fn apply(m: &[[f64; 3]; 3], v: DVec3) -> DVec3 {
    let r = |i: usize| m[i][0] * v.x + m[i][1] * v.y + m[i][2] * v.z;
    DVec3::new(r(0), r(1), r(2))
}

/// One transform level: rotation rows and translation.
#[derive(Clone, Copy)]
struct Level {
    rot: Option<u8>,
    t: IVec3,
}

/// The cell a voxel lands in, in MagicaVoxel coordinates, through `levels` (outermost
/// first): ⌊R·(v + ½ − ⌊s/2⌋) + t⌋ with R, t composed over the levels.
fn expected_cell(v: IVec3, size: IVec3, levels: &[Level]) -> IVec3 {
    let mut p = v.as_dvec3() + 0.5 - (size / 2).as_dvec3();
    for l in levels.iter().rev() {
        if let Some(b) = l.rot {
            p = apply(&rows_of(b).unwrap(), p);
        }
        p += l.t.as_dvec3();
    }
    p.floor().as_ivec3()
}

/// MagicaVoxel cell → voxbrick cell (z-up → y-up), as the importer documents it.
fn ours(c: IVec3) -> IVec3 {
    IVec3::new(c.x, c.z, -c.y - 1)
}

fn frame(t: IVec3, rot: Option<u8>) -> Frame {
    let mut d = Dict::new();
    d.insert("_t".into(), format!("{} {} {}", t.x, t.y, t.z));
    if let Some(r) = rot {
        d.insert("_r".into(), r.to_string());
    }
    Frame::new(d)
}

/// A scene graph: root transform → group → per instance (transform → [group → transform]
/// → shape). Each instance is (model, outer level, optional inner level).
fn scene(models: &[Model], instances: &[(u32, Level, Option<Level>)]) -> DotVoxData {
    let mut scenes = vec![
        SceneNode::Transform {
            attributes: Dict::new(),
            frames: vec![frame(IVec3::ZERO, None)],
            child: 1,
            layer_id: 0,
        },
        SceneNode::Group {
            attributes: Dict::new(),
            children: Vec::new(),
        },
    ];
    let mut children = Vec::new();
    for &(model, outer, inner) in instances {
        children.push(scenes.len() as u32);
        let shape_at = scenes.len() as u32 + if inner.is_some() { 3 } else { 1 };
        scenes.push(SceneNode::Transform {
            attributes: Dict::new(),
            frames: vec![frame(outer.t, outer.rot)],
            child: scenes.len() as u32 + 1,
            layer_id: 0,
        });
        if let Some(inner) = inner {
            scenes.push(SceneNode::Group {
                attributes: Dict::new(),
                children: vec![scenes.len() as u32 + 1],
            });
            scenes.push(SceneNode::Transform {
                attributes: Dict::new(),
                frames: vec![frame(inner.t, inner.rot)],
                child: shape_at,
                layer_id: 0,
            });
        }
        scenes.push(SceneNode::Shape {
            attributes: Dict::new(),
            models: vec![ShapeModel {
                model_id: model,
                attributes: Dict::new(),
            }],
        });
    }
    scenes[1] = SceneNode::Group {
        attributes: Dict::new(),
        children,
    };
    DotVoxData {
        version: 150,
        index_map: DEFAULT_INDEX_MAP.to_vec(),
        models: models.iter().map(copy_model).collect(),
        palette: DEFAULT_PALETTE.to_vec(),
        materials: vec![],
        scenes,
        layers: vec![Layer {
            attributes: Dict::new(),
        }],
    }
}

fn copy_model(m: &Model) -> Model {
    Model {
        size: Size {
            x: m.size.x,
            y: m.size.y,
            z: m.size.z,
        },
        voxels: m
            .voxels
            .iter()
            .map(|v| Voxel {
                x: v.x,
                y: v.y,
                z: v.z,
                i: v.i,
            })
            .collect(),
    }
}

/// A full box model whose voxels carry position-dependent palette indices (so a mirror or a
/// swap inside the box shows).
fn box_model(size: IVec3) -> Model {
    let mut voxels = Vec::new();
    for z in 0..size.z {
        for y in 0..size.y {
            for x in 0..size.x {
                voxels.push(Voxel {
                    x: x as u8,
                    y: y as u8,
                    z: z as u8,
                    i: colour_of(IVec3::new(x, y, z)),
                });
            }
        }
    }
    Model {
        size: Size {
            x: size.x as u32,
            y: size.y as u32,
            z: size.z as u32,
        },
        voxels,
    }
}

/// Palette index (dot_vox's, i.e. file index − 1) of a model voxel: distinct along each axis.
fn colour_of(v: IVec3) -> u8 {
    (1 + v.x + 5 * v.y + 25 * v.z) as u8
}

/// Imports and returns (voxbrick cell, sRGB colour) of every voxel.
fn imported(data: &DotVoxData) -> BTreeSet<([i32; 3], [u8; 3])> {
    let mut bytes = Vec::new();
    data.write_vox(&mut bytes).unwrap();
    let (scene, _) = common::import(&bytes, "t.vox");
    let flat = cells_of(&scene.world);
    // Imported as objects, the composite is the same world.
    let objects = vox::import_objects(&bytes, Path::new("t.vox"), 1).unwrap();
    assert_eq!(
        cells_of(&objects.scene.world),
        flat,
        "the objects' composite differs from the flattened import"
    );
    flat
}

fn cells_of(world: &brickmap::World) -> BTreeSet<([i32; 3], [u8; 3])> {
    let view = world.read();
    let table = view.materials();
    let d = view.dims().voxels();
    let mut out = BTreeSet::new();
    for x in 0..d.x {
        for y in 0..d.y {
            for z in 0..d.z {
                let p = IVec3::new(x, y, z);
                if let Some(m) = view.voxel(p).unwrap() {
                    out.insert((p.to_array(), table.colour(table.get(m).unwrap().colour)));
                }
            }
        }
    }
    out
}

/// The expected set: formula cells → voxbrick axes → shifted like the importer (each axis by
/// max(0, −min)).
fn expected(
    models: &[Model],
    instances: &[(u32, Level, Option<Level>)],
) -> BTreeSet<([i32; 3], [u8; 3])> {
    let mut cells = Vec::new();
    for &(model, outer, inner) in instances {
        let m = &models[model as usize];
        let size = IVec3::new(m.size.x as i32, m.size.y as i32, m.size.z as i32);
        let levels: Vec<Level> = std::iter::once(outer).chain(inner).collect();
        for v in &m.voxels {
            let v3 = IVec3::new(v.x as i32, v.y as i32, v.z as i32);
            let c = DEFAULT_PALETTE[v.i as usize];
            cells.push((ours(expected_cell(v3, size, &levels)), [c.r, c.g, c.b]));
        }
    }
    let lo = cells.iter().fold(IVec3::MAX, |m, (p, _)| m.min(*p));
    let shift = (-lo).max(IVec3::ZERO);
    cells
        .into_iter()
        .map(|(p, c)| ((p + shift).to_array(), c))
        .collect()
}

const ANCHOR: Level = Level {
    rot: None,
    t: IVec3::ZERO,
};

#[test]
fn an_odd_model_under_a_rotation_that_negates_x_sits_beside_its_unrotated_copy() {
    // A 3 × 2 × 1 model (pivot ⌊s/2⌋ = (1, 1, 0)) at t = (10, 0, 0) as is and at
    // t = (20, 0, 0) rotated by diag(−1, −1, 1) (byte: row 0 → col 0 negative, row 1 → col 1
    // negative: 0 | 1 << 2 | 1 << 4 | 1 << 5). Worked by hand: v = (0, 0, 0) has centre
    // (0.5, 0.5, 0.5) − (1, 1, 0) = (−0.5, −0.5, 0.5); unrotated it lands in
    // ⌊(9.5, −0.5, 0.5)⌋ = (9, −1, 0); rotated in ⌊(20.5, 0.5, 0.5)⌋ = (20, 0, 0).
    let rot = 1 << 2 | 1 << 4 | 1 << 5;
    assert_eq!(
        rows_of(rot),
        Some([[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]])
    );
    let models = vec![box_model(IVec3::new(3, 2, 1))];
    let at = |x| Level {
        rot: None,
        t: IVec3::new(x, 0, 0),
    };
    assert_eq!(
        expected_cell(IVec3::ZERO, IVec3::new(3, 2, 1), &[at(10)]),
        IVec3::new(9, -1, 0)
    );
    let r = Level {
        rot: Some(rot),
        t: IVec3::new(20, 0, 0),
    };
    assert_eq!(
        expected_cell(IVec3::ZERO, IVec3::new(3, 2, 1), &[r]),
        IVec3::new(20, 0, 0)
    );
    // The far corner (2, 1, 0): unrotated (11, 0, 0); rotated ⌊(20 − 1.5, −0.5, 0.5)⌋ = (18, −1, 0).
    assert_eq!(
        expected_cell(IVec3::new(2, 1, 0), IVec3::new(3, 2, 1), &[r]),
        IVec3::new(18, -1, 0)
    );
    let instances = [(0, at(10), None), (0, r, None)];
    assert_eq!(
        imported(&scene(&models, &instances)),
        expected(&models, &instances)
    );
}

#[test]
fn every_rotation_of_models_of_sizes_one_to_five_lands_where_the_formula_puts_it() {
    let sizes: Vec<IVec3> = (1..=5)
        .flat_map(|x| (1..=5).flat_map(move |y| (1..=5).map(move |z| IVec3::new(x, y, z))))
        .collect();
    let mut models: Vec<Model> = sizes.iter().map(|s| box_model(*s)).collect();
    models.push(box_model(IVec3::ONE));
    let anchor = models.len() as u32 - 1;
    let mut rotations = 0;
    for byte in 0..=127u8 {
        if rows_of(byte).is_none() {
            continue;
        }
        rotations += 1;
        // Each size on its own 8-voxel lattice cell, rotated; an unrotated 1³ anchor pins
        // the absolute position (a whole-scene shift cannot hide an error).
        let mut instances = vec![(anchor, ANCHOR, None)];
        for (k, _) in sizes.iter().enumerate() {
            let k = k as i32;
            let t = IVec3::new(k % 5, k / 5 % 5, k / 25) * 8 + 4;
            instances.push((k as u32, Level { rot: Some(byte), t }, None));
        }
        let got = imported(&scene(&models, &instances));
        let want = expected(&models, &instances);
        assert_eq!(got.len(), want.len(), "rotation byte {byte}");
        let wrong: Vec<_> = want.symmetric_difference(&got).take(4).collect();
        assert!(wrong.is_empty(), "rotation byte {byte}: {wrong:?}");
    }
    assert_eq!(rotations, 48);
}

#[test]
fn nested_group_transforms_compose_before_the_floor() {
    let models = vec![
        box_model(IVec3::new(3, 4, 5)),
        box_model(IVec3::new(2, 3, 1)),
        box_model(IVec3::ONE),
    ];
    // Outer rotations and translations with inner ones; odd and even sizes.
    let instances = [
        (2, ANCHOR, None),
        (
            0,
            Level {
                rot: Some(1 | 1 << 4),
                t: IVec3::new(30, 3, 7),
            },
            Some(Level {
                rot: Some(2 | 1 << 2 | 1 << 6),
                t: IVec3::new(-5, 4, 1),
            }),
        ),
        (
            1,
            Level {
                rot: Some(4 | 1 << 5),
                t: IVec3::new(12, 20, 9),
            },
            Some(Level {
                rot: Some(1 << 2 | 1 << 4 | 1 << 5),
                t: IVec3::new(3, -2, 0),
            }),
        ),
    ];
    assert_eq!(
        imported(&scene(&models, &instances)),
        expected(&models, &instances)
    );
}

#[test]
fn a_rotated_multi_model_scene_survives_export_and_import_voxel_for_voxel() {
    let models = vec![
        box_model(IVec3::new(3, 2, 5)),
        box_model(IVec3::new(4, 5, 3)),
        box_model(IVec3::ONE),
    ];
    let instances = [
        (2, ANCHOR, None),
        (
            0,
            Level {
                rot: Some(1 | 1 << 4 | 1 << 6),
                t: IVec3::new(9, 8, 7),
            },
            None,
        ),
        (
            1,
            Level {
                rot: Some(2 | 1 << 5),
                t: IVec3::new(20, 5, 3),
            },
            None,
        ),
        (
            0,
            Level {
                rot: Some(6 | 1 << 4),
                t: IVec3::new(4, 18, 12),
            },
            None,
        ),
    ];
    let data = scene(&models, &instances);
    let mut bytes = Vec::new();
    data.write_vox(&mut bytes).unwrap();
    let (first, _) = common::import(&bytes, "a.vox");
    assert_eq!(cells_of(&first.world), expected(&models, &instances));
    let exported = vox::export_data(&first.world).unwrap();
    let mut again = Vec::new();
    exported.write_vox(&mut again).unwrap();
    let (second, _) = vox::import_bytes(
        &again,
        Path::new("b.vox"),
        &vox::ImportOptions::default(),
        1,
    )
    .unwrap();
    assert_eq!(cells_of(&second.world), cells_of(&first.world));
}

#[test]
fn an_imported_model_is_framed_whole_by_its_camera() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../assets/vox/ogt_test_multiple_model_scene.vox");
    let (scene, _) = vox::import_file(&path, &vox::ImportOptions::default(), 1).unwrap();
    let c = &scene.params.camera;
    c.validate().unwrap();
    let d = scene.world.dims().voxels().as_dvec3();
    let aspect = 16.0 / 9.0;
    let (f, r, u) = c.basis(aspect);
    // Every corner of the content (here the whole grid: it is sized to fit) is in view.
    for k in 0..8 {
        let p = DVec3::new(
            if k & 1 == 0 { 0.0 } else { d.x },
            if k & 2 == 0 { 0.0 } else { d.y },
            if k & 4 == 0 { 0.0 } else { d.z },
        );
        let v = p - c.position;
        let z = v.dot(f);
        assert!(z > 0.0, "corner {k} behind the camera");
        let (x, y) = (
            v.dot(r) / r.length_squared() / z,
            v.dot(u) / u.length_squared() / z,
        );
        assert!(
            x.abs() <= 1.0 && y.abs() <= 1.0,
            "corner {k} at ({x:.2}, {y:.2})"
        );
    }
}

fn import_err(bytes: &[u8]) -> String {
    match vox::import_bytes(bytes, Path::new("x.vox"), &vox::ImportOptions::default(), 1) {
        Ok(_) => panic!("imported"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn several_models_without_a_scene_graph_are_frames_and_only_the_first_is_kept() {
    // Three frames of a 2 × 1 × 1 model, each a different voxel: stacking them would give 3.
    let frames: Vec<Model> = (0..3u8)
        .map(|k| Model {
            size: Size { x: 3, y: 1, z: 1 },
            voxels: vec![Voxel {
                x: k,
                y: 0,
                z: 0,
                i: 10 + k,
            }],
        })
        .collect();
    let bytes = common::vox_bytes(frames, vec![], vec![], vec![]);
    let (scene, report) = common::import(&bytes, "anim.vox");
    assert_eq!(scene.world.read().solid_count(), 1, "only the first frame");
    let c = DEFAULT_PALETTE[10];
    assert!(
        cells_of(&scene.world)
            .iter()
            .all(|(_, rgb)| *rgb == [c.r, c.g, c.b])
    );
    assert!(
        report
            .dropped
            .iter()
            .any(|d| d.contains("animation frames after the first ignored (×2")),
        "{:?}",
        report.dropped
    );
}

#[test]
fn a_shape_whose_voxels_are_in_an_unread_chunk_names_that_chunk() {
    // A scene graph whose second shape uses model 1, whose voxels a Teardown file keeps in
    // a TDCZ chunk: only model 0 is a SIZE/XYZI pair.
    let models = vec![box_model(IVec3::ONE), box_model(IVec3::ONE)];
    let mut data = scene(&models, &[(0, ANCHOR, None), (1, ANCHOR, None)]);
    data.models.truncate(1);
    let mut bytes = Vec::new();
    data.write_vox(&mut bytes).unwrap();
    // Without any other chunk, the plain message.
    let plain = import_err(&bytes);
    assert!(
        plain.contains("missing model 1") && !plain.contains("TDCZ"),
        "{plain}"
    );
    // Append a TDCZ chunk to MAIN's children (its children size is at byte 16).
    let payload = [7u8; 20];
    bytes.extend_from_slice(b"TDCZ");
    bytes.extend_from_slice(&(payload.len() as u32).to_le_bytes());
    bytes.extend_from_slice(&0u32.to_le_bytes());
    bytes.extend_from_slice(&payload);
    let children =
        u32::from_le_bytes(bytes[16..20].try_into().unwrap()) + 12 + payload.len() as u32;
    bytes[16..20].copy_from_slice(&children.to_le_bytes());
    let named = import_err(&bytes);
    assert!(
        named.contains("missing model 1")
            && named.contains("TDCZ (Teardown's compressed voxel data)"),
        "{named}"
    );
}

#[test]
fn a_slab6_vox_is_named_as_such() {
    let (x, y, z) = (2u32, 3u32, 4u32);
    let mut bytes = Vec::new();
    for d in [x, y, z] {
        bytes.extend_from_slice(&d.to_le_bytes());
    }
    bytes.extend(std::iter::repeat_n(255u8, (x * y * z) as usize));
    bytes.extend(std::iter::repeat_n(32u8, 768));
    let e = import_err(&bytes);
    assert!(e.contains("SLAB6") && e.contains("2×3×4"), "{e}");
    // One byte more or less is not SLAB6: the usual error.
    bytes.push(0);
    assert!(!import_err(&bytes).contains("SLAB6"));
}
