//! MagicaVoxel files: every sample imported (flattened and as objects), objects through
//! export and import, scene graphs, rotations, scenes beyond 256³, MATL materials, hostile
//! files, models over 256 as chunks.

use super::*;

#[test]
fn every_sample_vox_imports_and_the_invalid_one_is_an_error() {
    let mut imported = 0;
    for entry in std::fs::read_dir(assets()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("vox") {
            continue;
        }
        let result = vox::import_file(&path, &vox::ImportOptions::default(), 2);
        if path.file_name().unwrap() == "dotvox_not_a.vox" {
            let err = result
                .expect_err("the invalid sample is refused")
                .to_string();
            assert!(
                err.contains("dotvox_not_a.vox") && err.contains("not a valid .vox"),
                "{err}"
            );
            continue;
        }
        let (scene, report) = result.unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(report.voxels > 0, "{}", path.display());
        assert_eq!(scene.world.read().solid_count(), report.voxels);
        scene.world.read().validate().unwrap();
        imported += 1;
    }
    assert_eq!(imported, 17);
}

/// The valid sample `.vox` files.
fn sample_vox_files() -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(assets())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.extension().and_then(|e| e.to_str()) == Some("vox")
                && p.file_name().unwrap() != "dotvox_not_a.vox"
        })
        .collect();
    out.sort();
    out
}

/// Positions made relative to the lowest corner of the content (imports may shift
/// differently), sorted.
fn relative(
    mut cells: Vec<(IVec3, MaterialKind, u32, [u8; 3])>,
) -> Vec<(IVec3, MaterialKind, u32, [u8; 3])> {
    let lo = cells.iter().fold(IVec3::MAX, |m, c| m.min(c.0));
    for c in &mut cells {
        c.0 -= lo;
    }
    cells.sort_by_key(|v| (v.0.x, v.0.y, v.0.z));
    cells
}

#[test]
fn every_sample_vox_imported_as_objects_composites_to_the_flattened_import() {
    let mut compared = 0;
    for path in sample_vox_files() {
        let bytes = std::fs::read(&path).unwrap();
        let (flat, report) =
            vox::import_bytes(&bytes, &path, &vox::ImportOptions::default(), 2).unwrap();
        let objects = vox::import_objects(&bytes, &path, 2).unwrap();
        let name = path.display();
        assert_eq!(
            relative(resolved(&objects.scene.world)),
            relative(resolved(&flat.world)),
            "{name}"
        );
        assert_eq!(objects.report.instances, report.instances, "{name}");
        assert_eq!(objects.report.voxels, report.voxels, "{name}");
        objects.scene.world.read().validate().unwrap();
        // Every object's model is one of the file's, shared where the file shares it.
        let objects = objects.scene.objects();
        let tree = objects.tree();
        let placed: usize = objects
            .models()
            .keys()
            .map(|m| tree.instances(*m).len())
            .sum();
        assert_eq!(placed, report.instances, "{name}: objects = instances");
        compared += 1;
    }
    assert_eq!(compared, 17);
}

#[test]
fn objects_survive_export_and_import_with_names_hidden_flags_layers_and_shared_models() {
    use brickmap::objects::{LayerId, NodeKind, ObjectOp, ObjectTree};
    let dir = scratch("objects-round-trip");
    let mut compared = 0;
    for path in sample_vox_files() {
        let name = path.display().to_string();
        let first = vox::import_objects(&std::fs::read(&path).unwrap(), &path, 2).unwrap();
        // Hide the last object and its layer's neighbour, so flags travel too.
        let table = first.scene.world.materials().clone();
        let last = *first
            .scene
            .objects()
            .tree()
            .subtree(ObjectTree::ROOT)
            .unwrap()
            .last()
            .unwrap();
        let is_object = matches!(
            first.scene.objects().tree().node(last).unwrap().kind,
            NodeKind::Object { .. }
        );
        if is_object {
            let hide = ObjectOp::Show {
                node: last,
                visible: false,
            };
            first.scene.apply(hide).unwrap();
        }
        let second_layer = first.scene.objects().tree().layers().len() > 1;
        if second_layer {
            let hide = ObjectOp::ShowLayer {
                layer: LayerId(1),
                visible: false,
            };
            first.scene.apply(hide).unwrap();
        }
        let out = dir.join("round.vox");
        let report = vox::export_file(&first.scene, &out).unwrap();
        let second = vox::import_objects(&std::fs::read(&out).unwrap(), &out, 2).unwrap();
        let (first_objects, second_objects) = (first.scene.objects(), second.scene.objects());
        assert_eq!(
            outline(&second_objects, &second.scene.world.materials()),
            outline(&first_objects, &table),
            "{name}"
        );
        assert_eq!(
            second_objects.tree().layers(),
            first_objects.tree().layers(),
            "{name}"
        );
        assert_eq!(second_objects.models().len(), report.models, "{name}");
        // Shared models stay shared: the same numbers of instances per model.
        let sharing = |o: &brickmap::objects::Objects| {
            let mut n: Vec<usize> = o
                .models()
                .keys()
                .map(|m| o.tree().instances(*m).len())
                .filter(|n| *n > 0)
                .collect();
            n.sort_unstable();
            n
        };
        assert_eq!(sharing(&second_objects), sharing(&first_objects), "{name}");
        assert_eq!(
            resolved(&second.scene.world),
            resolved(&first.scene.world),
            "{name}: the same voxels in the same places"
        );
        compared += 1;
    }
    assert_eq!(compared, 17);
}

#[test]
fn multi_model_scene_graph_places_every_instance() {
    let path = assets().join("ogt_test_multiple_model_scene.vox");
    let (_, report) = vox::import_file(&path, &vox::ImportOptions::default(), 2).unwrap();
    assert_eq!((report.models, report.instances), (41, 104));
    assert!(
        report.dropped.iter().any(|d| d.contains("rOBJ")),
        "{:?}",
        report.dropped
    );
    let with_hidden = vox::import_file(
        &path,
        &vox::ImportOptions {
            include_hidden: true,
            ..Default::default()
        },
        2,
    )
    .unwrap()
    .1;
    assert!(with_hidden.instances >= report.instances);
}

#[test]
fn import_export_import_keeps_voxels_and_materials() {
    for name in [
        "mmmm_scene_park.vox",
        "dotvox_metal-material.vox",
        "mmmm_veh_tank1.vox",
    ] {
        let (first, _) =
            vox::import_file(&assets().join(name), &vox::ImportOptions::default(), 2).unwrap();
        let d = scratch(&format!("vox-{name}"));
        let out = d.join("again.vox");
        vox::export_file(&first, &out).unwrap();
        let (second, _) = vox::import_file(&out, &vox::ImportOptions::default(), 2).unwrap();
        assert_eq!(resolved(&first.world), resolved(&second.world), "{name}");
    }
}

#[test]
fn scene_beyond_256_in_every_axis_survives_vox() {
    let scene = Scene::empty(GridDims::new(40, 36, 34).unwrap(), 2).unwrap(); // 320 × 288 × 272
    let w = &scene.world;
    let metal = w
        .push_material(Material {
            kind: MaterialKind::Metal,
            param: 20,
            colour: 40,
        })
        .unwrap();
    w.set_param(MaterialKind::Dielectric, 5, 1.7).unwrap();
    let glass = w
        .push_material(Material {
            kind: MaterialKind::Dielectric,
            param: 5,
            colour: 41,
        })
        .unwrap();
    w.set_param(MaterialKind::Emissive, 3, 12.0).unwrap();
    let lamp = w
        .push_material(Material {
            kind: MaterialKind::Emissive,
            param: 3,
            colour: 42,
        })
        .unwrap();
    let corners: Vec<VoxelEdit> = [
        IVec3::ZERO,
        IVec3::new(319, 287, 271),
        IVec3::new(319, 0, 0),
        IVec3::new(0, 287, 0),
        IVec3::new(0, 0, 271),
        IVec3::new(255, 256, 257),
    ]
    .into_iter()
    .zip([0, metal, glass, lamp, metal, glass])
    .map(|(pos, m)| VoxelEdit {
        pos,
        op: VoxelOp::Set(m),
    })
    .collect();
    scene.edit(EditOp::Voxels(corners)).unwrap();
    scene
        .edit(EditOp::Shape {
            shape: Shape::Sphere {
                centre: DVec3::new(256.0, 256.0, 256.0),
                radius: 12.0,
            },
            mode: Mode::Add(lamp),
        })
        .unwrap();
    let d = scratch("big");
    let out = d.join("big.vox");
    let report = vox::export_file(&scene, &out).unwrap();
    assert!(report.models > 1, "split into ≤256³ models: {report:?}");
    let (back, _) = vox::import_file(&out, &vox::ImportOptions::default(), 2).unwrap();
    assert_eq!(back.world.dims(), scene.world.dims());
    assert_eq!(resolved(&back.world), resolved(&scene.world));
}

#[test]
fn rotated_and_translated_instances_land_where_magicavoxel_puts_them() {
    use dot_vox::*;
    // One 3×1×1 model (voxels at x = 0, 1, 2 with colours 1, 2, 3) placed twice: as is at
    // t = (10, 0, 0), and rotated 90° about z (x → y) at t = (0, 10, 0).
    let model = Model {
        size: Size { x: 3, y: 1, z: 1 },
        voxels: (0..3)
            .map(|x| Voxel {
                x,
                y: 0,
                z: 0,
                i: x,
            })
            .collect(),
    };
    let frame = |t: &str, r: Option<&str>| {
        let mut d = Dict::new();
        d.insert("_t".into(), t.into());
        if let Some(r) = r {
            d.insert("_r".into(), r.into());
        }
        Frame::new(d)
    };
    // Row 0 = (0, -1, 0): bits 0-1 = 1, sign bit 4 set; row 1 = (1, 0, 0): bits 2-3 = 0.
    let rot = (1 | (1 << 4)).to_string(); // row 0 → column 1, negative; row 1 → column 0
    let scenes = vec![
        SceneNode::Transform {
            attributes: Dict::new(),
            frames: vec![frame("0 0 0", None)],
            child: 1,
            layer_id: 0,
        },
        SceneNode::Group {
            attributes: Dict::new(),
            children: vec![2, 4],
        },
        SceneNode::Transform {
            attributes: Dict::new(),
            frames: vec![frame("10 0 0", None)],
            child: 3,
            layer_id: 0,
        },
        SceneNode::Shape {
            attributes: Dict::new(),
            models: vec![ShapeModel {
                model_id: 0,
                attributes: Dict::new(),
            }],
        },
        SceneNode::Transform {
            attributes: Dict::new(),
            frames: vec![frame("0 10 0", Some(&rot))],
            child: 5,
            layer_id: 0,
        },
        SceneNode::Shape {
            attributes: Dict::new(),
            models: vec![ShapeModel {
                model_id: 0,
                attributes: Dict::new(),
            }],
        },
    ];
    let bytes = common::vox_bytes(
        vec![model],
        vec![],
        scenes,
        vec![Layer {
            attributes: Dict::new(),
        }],
    );
    let (scene, report) = common::import(&bytes, "rot.vox");
    assert_eq!(report.instances, 2);
    // MagicaVoxel coordinates, ⌊R·(v + ½ − ⌊s/2⌋) + t⌋ with pivot ⌊(3, 1, 1)/2⌋ = (1, 0, 0):
    // unrotated, v = (x, 0, 0) has centre (x − ½, ½, ½) and lands at (x + 9, 0, 0); rotated
    // (rows (0, −1, 0), (1, 0, 0), (0, 0, 1)) the centre becomes (−½, x − ½, ½) and lands at
    // (−1, x + 9, 0) — one voxel further than a pivot of s/2 put it (tests/vox_pivot.rs
    // checks every rotation).
    let expected_vox = [
        (IVec3::new(9, 0, 0), 0u8),
        (IVec3::new(10, 0, 0), 1),
        (IVec3::new(11, 0, 0), 2),
        (IVec3::new(-1, 9, 0), 0),
        (IVec3::new(-1, 10, 0), 1),
        (IVec3::new(-1, 11, 0), 2),
    ];
    // To voxbrick axes, then shifted so the minimum is 0 on every axis.
    let ours: Vec<(IVec3, u8)> = expected_vox
        .iter()
        .map(|(v, i)| (IVec3::new(v.x, v.z, -v.y - 1), *i))
        .collect();
    let lo = ours.iter().fold(IVec3::MAX, |m, (p, _)| m.min(*p));
    let view = scene.world.read();
    let table = view.materials();
    for (p, i) in ours {
        let m = view
            .voxel(p - lo)
            .unwrap()
            .unwrap_or_else(|| panic!("no voxel at {}", p - lo));
        let c = DEFAULT_PALETTE[i as usize];
        assert_eq!(table.colour(table.get(m).unwrap().colour), [c.r, c.g, c.b]);
    }
    assert_eq!(view.solid_count(), 6);
}

#[test]
fn import_into_an_existing_world_merges_materials() {
    let scene = default_scene(SceneSize::Small, 2).unwrap();
    let before = scene.world.read().solid_count();
    let materials = scene.world.materials().len();
    let bytes = std::fs::read(assets().join("mmmm_chr_robot.vox")).unwrap();
    let at = |x, y, z| vox::ImportOptions {
        offset: IVec3::new(x, y, z),
        ..Default::default()
    };
    let (report, edit) = vox::import_into(&scene.world, &bytes, &at(10, 40, 10), None).unwrap();
    scene.edit(edit).unwrap();
    assert!(report.voxels > 0 && report.dropped.is_empty(), "{report:?}");
    assert!(scene.world.materials().len() > materials);
    assert!(scene.world.read().solid_count() > before);
    // Again elsewhere: identical materials and colours are reused, not duplicated.
    let len = scene.world.materials().len();
    vox::import_into(&scene.world, &bytes, &at(60, 40, 60), None).unwrap();
    // Poking out of the top: the outside part is dropped and reported.
    let (clipped, _) = vox::import_into(&scene.world, &bytes, &at(90, 60, 90), None).unwrap();
    assert!(
        clipped
            .dropped
            .iter()
            .any(|d| d.contains("outside the grid")),
        "{:?}",
        clipped.dropped
    );
    assert_eq!(scene.world.materials().len(), len);
}

#[test]
fn matl_materials_map_to_voxbrick_materials() {
    use dot_vox::*;
    let matl = |id: u32, props: &[(&str, &str)]| Material {
        id,
        properties: props
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
    };
    // MATL ids are the file's palette indices: voxel i uses MATL i + 1.
    let bytes = common::vox_bytes(
        vec![Model {
            size: Size { x: 7, y: 1, z: 1 },
            voxels: (0..7)
                .map(|x| Voxel {
                    x,
                    y: 0,
                    z: 0,
                    i: x,
                })
                .collect(),
        }],
        vec![
            matl(1, &[("_type", "_diffuse")]),
            matl(
                2,
                &[("_type", "_metal"), ("_rough", "0.5"), ("_metal", "1")],
            ),
            matl(3, &[("_type", "_glass"), ("_ior", "0.3")]),
            matl(4, &[("_type", "_glass"), ("_ri", "1.7"), ("_ior", "0.9")]),
            matl(5, &[("_type", "_emit"), ("_emit", "0.5"), ("_flux", "2")]),
            matl(6, &[("_type", "_cloud")]),
        ],
        vec![],
        vec![],
    );
    let (scene, report) = common::import(&bytes, "matl.vox");
    let view = scene.world.read();
    let table = view.materials();
    let at = |x: i32| {
        let m = table
            .get(view.voxel(IVec3::new(x, 0, 0)).unwrap().unwrap())
            .unwrap();
        (m.kind, table.param(m.kind, m.param).unwrap())
    };
    assert_eq!(at(0).0, MaterialKind::Lambertian);
    assert_eq!(at(1), (MaterialKind::Metal, 32.0 / 63.0));
    assert_eq!(at(2).0, MaterialKind::Dielectric);
    assert!(
        (at(2).1 - 1.3).abs() < 1e-6,
        "ior − 1 convention: {}",
        at(2).1
    );
    assert!((at(3).1 - 1.7).abs() < 1e-6, "_ri wins: {}", at(3).1);
    assert_eq!(at(4), (MaterialKind::Emissive, 2.0));
    assert_eq!(at(5).0, MaterialKind::Lambertian);
    assert_eq!(at(6).0, MaterialKind::Lambertian, "no MATL: diffuse");
    assert!(
        report.dropped.iter().any(|d| d.contains("_cloud")),
        "{:?}",
        report.dropped
    );
}

/// Hostile or damaged .vox files are refused with the chunk and its byte offset, and nothing
/// is written; a file whose every model is left out is an error saying why, not an empty
/// success. (The seeds in app/fuzz/seeds/vox_import are these files.)
#[test]
fn hostile_vox_files_are_refused_and_nothing_left_out_silently() {
    let seeds = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds/vox_import");
    let dir = scratch("hostile");
    for (file, want) in [
        (
            "huge_model_empty_xyzi.vox",
            "chunk SIZE at byte 20 declares a 2000000000 × 2000000000 × 2000000000 model",
        ),
        (
            "count_beyond_bytes.vox",
            "chunk XYZI at byte 44 claims 1000 voxels but holds 1",
        ),
        (
            "voxel_outside_model.vox",
            "voxel 1 at (9, 0, 0) lies outside its 4 × 4 × 4 model",
        ),
        ("truncated.vox", "the file ends 5 bytes short (truncated)"),
        ("size_without_xyzi.vox", "has no XYZI chunk after it"),
        ("zero_size.vox", "declares a 0 × 4 × 4 model"),
    ] {
        let e = vox::import_file(&seeds.join(file), &vox::ImportOptions::default(), 1)
            .map(|_| ())
            .unwrap_err();
        assert!(
            matches!(
                e,
                FormatError::Vox {
                    error: vox::VoxError::Malformed(_),
                    ..
                }
            ),
            "{file}: {e}"
        );
        assert!(e.to_string().contains(want), "{file}: {e}");
        // Imported as objects: the same checks, the same error.
        let bytes = std::fs::read(seeds.join(file)).unwrap();
        let as_objects = vox::import_objects(&bytes, &seeds.join(file), 1)
            .map(|_| ())
            .unwrap_err();
        assert_eq!(as_objects.to_string(), e.to_string(), "{file}");
        // The command line: a one-line error, exit non-zero, nothing written.
        let out = dir.join(format!("{file}.ron"));
        let run = std::process::Command::new(env!("CARGO_BIN_EXE_voxbrick"))
            .arg("convert")
            .arg(seeds.join(file))
            .arg(&out)
            .output()
            .unwrap();
        assert!(!run.status.success(), "{file}");
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(stderr.trim_end().lines().count(), 1, "{file}: {stderr}");
        assert!(!out.exists(), "{file}: nothing is written");
    }

    // Every model on a hidden layer: an error naming why; with hidden nodes included, the
    // import works.
    use dot_vox::*;
    let model = Model {
        size: Size { x: 2, y: 2, z: 2 },
        voxels: vec![
            Voxel {
                x: 0,
                y: 0,
                z: 0,
                i: 5,
            },
            Voxel {
                x: 1,
                y: 1,
                z: 1,
                i: 6,
            },
        ],
    };
    let mut hidden_layer = Dict::new();
    hidden_layer.insert("_hidden".into(), "1".into());
    let scenes = vec![
        SceneNode::Transform {
            attributes: Dict::new(),
            frames: vec![Frame::new(Dict::new())],
            child: 1,
            layer_id: 0,
        },
        SceneNode::Shape {
            attributes: Dict::new(),
            models: vec![ShapeModel {
                model_id: 0,
                attributes: Dict::new(),
            }],
        },
    ];
    let bytes = common::vox_bytes(
        vec![model],
        vec![],
        scenes,
        vec![Layer {
            attributes: hidden_layer,
        }],
    );
    let e = vox::import_bytes(
        &bytes,
        Path::new("hidden.vox"),
        &vox::ImportOptions::default(),
        1,
    )
    .map(|_| ())
    .unwrap_err();
    let text = e.to_string();
    assert!(
        text.contains("nothing to import") && text.contains("hidden layer 0 skipped"),
        "{text}"
    );
    let (scene, report) = vox::import_bytes(
        &bytes,
        Path::new("hidden.vox"),
        &vox::ImportOptions {
            include_hidden: true,
            ..Default::default()
        },
        1,
    )
    .unwrap();
    assert_eq!(report.voxels, 2);
    assert_eq!(scene.world.read().solid_count(), 2);
    // Importing into a world where every voxel lands outside the grid: an error, no edit.
    let world = Scene::empty(GridDims::new(1, 1, 1).unwrap(), 1)
        .unwrap()
        .world;
    let before = world.read().content_hash();
    let e = vox::import_into(
        &world,
        &bytes,
        &vox::ImportOptions {
            include_hidden: true,
            offset: IVec3::new(100, 0, 0),
        },
        None,
    )
    .map(|_| ())
    .unwrap_err();
    assert!(matches!(e, vox::VoxError::OutsideGrid { .. }), "{e}");
    assert!(e.to_string().contains("outside the"), "{e}");
    assert_eq!(world.read().content_hash(), before);
}

#[test]
fn a_model_over_256_leaves_as_chunks_under_a_group_and_comes_back_in_place() {
    use brickmap::objects::{
        Axis, LayerId, Model, ModelId, NewNode, NodeKind, ObjectTree, Objects, Orientation,
        Placement,
    };
    let dir = scratch("vox-chunks");
    let scene = Scene::empty(GridDims::new(48, 40, 40).unwrap(), 2).unwrap();
    let table = scene.world.materials().clone();
    // An odd-sized model, longer than 256, with an asymmetric hollow.
    let size = IVec3::new(300, 21, 13);
    let mut model = Model::new(size).unwrap();
    for (shape, mode) in [
        (
            Shape::Box {
                min: IVec3::ZERO,
                max: size - 1,
            },
            Mode::Add(0),
        ),
        (
            Shape::Sphere {
                centre: DVec3::new(40.0, 15.0, 3.0),
                radius: 9.0,
            },
            Mode::Remove,
        ),
    ] {
        model.apply(&EditOp::Shape { shape, mode }, &table).unwrap();
    }
    let mut tree = ObjectTree::new();
    let turned = Placement {
        rot: Orientation::quarter_turn(Axis::Y, 1).after(&Orientation::flip(Axis::X)),
        t: IVec3::new(150, 160, 160),
    };
    let object = NewNode::Object {
        model: ModelId(0),
        layer: LayerId(0),
    };
    tree.add(ObjectTree::ROOT, None, "long", turned, object)
        .unwrap();
    let models = std::collections::BTreeMap::from([(ModelId(0), model)]);
    let world = brickmap::World::new(
        GridDims::new(48, 40, 40).unwrap(),
        brickmap::WorldConfig::with_workers(2),
    )
    .unwrap();
    let objects = Objects::new(tree, models, &world).unwrap();
    let scene = Scene::with_objects(world, objects, None, scene.params.clone());
    let out = dir.join("long.vox");
    let report = vox::export_file(&scene, &out).unwrap();
    assert_eq!(report.models, 2, "two chunks");
    let back = vox::import_objects(&std::fs::read(&out).unwrap(), &out, 2).unwrap();
    // The original lies in the positive octant, so the import shifts nothing: the same
    // places, not only the same shape.
    assert_eq!(
        resolved(&back.scene.world),
        resolved(&scene.world),
        "the chunks land where the model's voxels were"
    );
    let objects = back.scene.objects();
    let tree = objects.tree();
    let group = tree.node(ObjectTree::ROOT).unwrap().children()[0];
    assert_eq!(tree.node(group).unwrap().name, "long");
    assert!(matches!(
        tree.node(group).unwrap().kind,
        NodeKind::Group { .. }
    ));
    assert_eq!(tree.node(group).unwrap().children().len(), 2);
}
