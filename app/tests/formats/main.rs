//! File formats end to end: project round trips and hostile files, atomic saves (here);
//! .vox import of every sample, import → export → import, scenes beyond 256³, rotations
//! (`vox_files.rs`); meshes out (`mesh.rs`); heightmaps in (`heightmap.rs`); finished
//! pictures out (`pictures.rs`); Qubicle and Sponge schematic files (`qubicle.rs`,
//! `schematics.rs`).

#[path = "../common/mod.rs"]
mod common;
mod heightmap;
mod mesh;
mod pictures;
mod qubicle;
mod schematics;
mod vox_files;

use app::Scene;
use app::builtin::{SceneSize, default_scene};
use app::formats::{FormatError, project, vox};
use brickmap::{EditOp, GridDims, Material, MaterialKind, Mode, Shape, VoxelEdit, VoxelOp, World};
use glam::{DVec3, IVec3};
use std::path::{Path, PathBuf};

/// A scratch folder for this test, removed when it passes.
fn scratch(name: &str) -> app::scratch::Scratch {
    app::scratch::Scratch::new(&format!("formats-{name}"))
}

fn assets() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/vox")
}

/// Every voxel with its resolved material (kind, parameter value, colour), for comparing
/// scenes whose tables are numbered differently.
fn resolved(world: &World) -> Vec<(IVec3, MaterialKind, u32, [u8; 3])> {
    let view = world.read();
    let table = view.materials();
    let mut out = Vec::new();
    view.for_each_brick(|b, mask, mats| {
        for (k, bit) in mask.ones().enumerate() {
            let m = match mats {
                brickmap::BrickMaterials::Uniform(m) => m,
                brickmap::BrickMaterials::PerVoxel(v) => v[k],
            };
            let mat = table.get(m).unwrap();
            let p = b.as_ivec3() * 8
                + IVec3::new((bit % 8) as i32, (bit / 8 % 8) as i32, (bit / 64) as i32);
            let param = table.param(mat.kind, mat.param).unwrap();
            out.push((
                p,
                mat.kind,
                (param * 1000.0).round() as u32,
                table.colour(mat.colour),
            ));
        }
    });
    out.sort_by_key(|v| (v.0.x, v.0.y, v.0.z));
    out
}

/// The files of `assets/DIR` ending in `.EXT`, sorted (at least `least` of them).
fn asset_files(dir: &str, ext: &str, least: usize) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../assets")
        .join(dir);
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == ext))
        .collect();
    out.sort();
    assert!(out.len() >= least, "{out:?}");
    out
}

/// `count` copies of `bytes`, each with 1 to 4 bytes overwritten at places and with values
/// drawn from a xorshift sequence seeded with `seed` (deterministic hostile inputs).
fn mutations(bytes: &[u8], count: usize, mut seed: u32) -> Vec<Vec<u8>> {
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        seed
    };
    (0..count)
        .map(|_| {
            let mut m = bytes.to_vec();
            for _ in 0..1 + next() % 4 {
                let r = next();
                let at = r as usize % m.len();
                m[at] = (r >> 8) as u8;
            }
            m
        })
        .collect()
}

/// [`resolved`] relative to the lowest corner of the voxels' box (scenes placed apart).
fn content(world: &World) -> Vec<(IVec3, MaterialKind, u32, [u8; 3])> {
    let all = resolved(world);
    let lo = all
        .iter()
        .map(|v| v.0)
        .reduce(IVec3::min)
        .unwrap_or(IVec3::ZERO);
    all.into_iter()
        .map(|(p, k, v, c)| (p - lo, k, v, c))
        .collect()
}

/// A tree in pre-order: each node's name, kind (for an object its model's voxels with their
/// resolved materials, which two imports may number differently), visibility, layer and
/// world placement.
fn outline(objects: &brickmap::objects::Objects, table: &brickmap::MaterialTable) -> Vec<String> {
    use std::hash::{Hash, Hasher};
    let content = |m: &brickmap::objects::Model| {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        m.size().to_array().hash(&mut h);
        for (b, brick) in m.bricks() {
            for bit in brick.mask.ones() {
                let mat = table.get(brick.material(bit)).unwrap();
                (b.to_array(), bit, mat.kind as u8, table.colour(mat.colour)).hash(&mut h);
                table
                    .param(mat.kind, mat.param)
                    .unwrap()
                    .to_bits()
                    .hash(&mut h);
            }
        }
        h.finish()
    };
    objects.outline(false, |_, m| format!("model {:x}", content(m)))
}

#[test]
fn project_round_trips_everything() {
    let mut scene = default_scene(SceneSize::Small, 2).unwrap();
    let params = &mut scene.params;
    params.camera.yaw_deg = 12.5;
    params.sky = render::Sky::Uniform {
        colour: [0.5, 0.25, 2.0],
    };
    params.sun.animate = true;
    params.settings.max_bounces = 7;
    let d = scratch("roundtrip");
    let path = d.join("scene.ron");
    app::formats::save(&scene, &path).unwrap();
    let loaded = app::formats::load(&path, 3).unwrap();
    assert_eq!(loaded.params, scene.params);
    assert_eq!(
        loaded.world.read().content_hash(),
        scene.world.read().content_hash()
    );
    assert_eq!(loaded.world.dims(), scene.world.dims());
    // Saving the loaded scene gives the same bytes.
    assert_eq!(
        project::to_string(&loaded),
        std::fs::read_to_string(&path).unwrap()
    );
    // A perspective camera is written without a projection (files stay as before); an
    // orthographic one round-trips, and a bad height is refused by name.
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(!text.contains("projection"));
    let mut ortho = app::formats::load(&path, 2).unwrap();
    ortho.params.camera.projection = render::Projection::Orthographic { height: 37.5 };
    let ortho_path = d.join("ortho.ron");
    app::formats::save(&ortho, &ortho_path).unwrap();
    let ortho_text = std::fs::read_to_string(&ortho_path).unwrap();
    assert!(ortho_text.contains("projection: Orthographic(height: 37.5)"));
    assert_eq!(
        app::formats::load(&ortho_path, 2).unwrap().params,
        ortho.params
    );
    std::fs::write(
        &ortho_path,
        ortho_text.replace("height: 37.5", "height: -1.0"),
    )
    .unwrap();
    let err = app::formats::load(&ortho_path, 2).unwrap_err().to_string();
    assert!(err.contains("orthographic height"), "{err}");
    // The non-voxel part is readable RON.
    assert!(
        text.contains("format_version: 2")
            && text.contains("kind: Metal")
            && text.contains("\"#56983a\""),
        "{}",
        &text[..600]
    );
}

#[test]
fn the_sample_sequence_is_saved_and_older_projects_load_with_the_default() {
    let mut scene = default_scene(SceneSize::Small, 2).unwrap();
    scene.params.settings.sequence = render::Sequence::Independent;
    let text = project::to_string(&scene);
    assert!(text.contains("sequence: Independent"), "{}", &text[..800]);
    let p = Path::new("test.ron");
    let back = project::from_bytes(text.as_bytes(), p, 2).unwrap();
    assert_eq!(back.params.settings.sequence, render::Sequence::Independent);
    // A project written before the setting existed: the default, scrambled Sobol.
    let old = text.replacen(", sequence: Independent", "", 1);
    assert!(!old.contains("sequence:"));
    let back = project::from_bytes(old.as_bytes(), p, 2).unwrap();
    assert_eq!(back.params.settings.sequence, render::Sequence::Sobol);
}

#[test]
fn versions_and_hostile_files_are_clear_errors() {
    // Version 1 (one grid): what older files hold; version 2's own are below.
    let scene = default_scene(SceneSize::Small, 2).unwrap();
    let text = project::grid_to_string(&scene);
    let p = Path::new("test.ron");
    let newer = text.replacen("format_version: 1", "format_version: 7", 1);
    match project::from_bytes(newer.as_bytes(), p, 2) {
        Err(FormatError::NewerVersion {
            found: 7, known: 2, ..
        }) => {}
        other => panic!("{:?}", other.err()),
    }
    let zero = text.replacen("format_version: 1", "format_version: 0", 1);
    assert!(
        project::from_bytes(zero.as_bytes(), p, 2)
            .unwrap_err()
            .to_string()
            .contains("never existed")
    );
    // Every truncation fails cleanly (sampled; the text is long).
    for cut in (0..text.trim_end().len()).step_by(97) {
        assert!(
            project::from_bytes(&text.as_bytes()[..cut], p, 2).is_err(),
            "cut at {cut}"
        );
    }
    let cases = [
        (
            text.replacen(
                "grid_bricks: (16, 8, 16)",
                "grid_bricks: (100000, 8, 16)",
                1,
            ),
            "grid",
        ),
        (
            text.replacen("grid_bricks: (16, 8, 16)", "grid_bricks: (2, 2, 2)", 1),
            "beyond the",
        ),
        (
            text.replacen("max_bounces: 3", "max_bounces: 0", 1),
            "max bounces",
        ),
        (
            text.replacen("kind: Metal, param: 8", "kind: Metal, param: 80", 1),
            "parameter index",
        ),
        (
            text.replacen("\"#56983a\"", "\"#zz983a\"", 1),
            "not #rrggbb",
        ),
        (
            text.replacen("encoding: \"vxb1-base64\"", "encoding: \"zstd\"", 1),
            "unknown voxel encoding",
        ),
        (
            text.replacen("solid_voxels: ", "solid_voxels: 1", 1),
            "header says",
        ),
        (text.replacen("data: \"VlhC", "data: \"AAAA", 1), "VXB1"),
        ("\u{0}\u{1}garbage".to_string(), "not a voxbrick project"),
        ("(foo: 1)".to_string(), "begins with `(format_version: 1,`"),
    ];
    for (bad, want) in cases {
        let err = project::from_bytes(bad.as_bytes(), p, 2)
            .unwrap_err()
            .to_string();
        assert!(err.contains(want), "expected {want:?} in: {err}");
        assert!(!err.contains("Probe"), "no internal names: {err}");
        assert!(
            err.starts_with("test.ron: "),
            "the error names the file: {err}"
        );
    }
    // Dropping materials the voxels use is refused.
    let start = text.find("materials: [").unwrap();
    let end = text[start..].find(']').unwrap() + start;
    let one = format!(
        "{}materials: [(kind: Lambertian, param: 0, colour: 1)]{}",
        &text[..start],
        &text[end + 1..]
    );
    assert!(
        project::from_bytes(one.as_bytes(), p, 2)
            .unwrap_err()
            .to_string()
            .contains("beyond the table")
    );
}

#[test]
fn failed_save_keeps_the_previous_file() {
    let scene = default_scene(SceneSize::Small, 2).unwrap();
    let d = scratch("failsave");
    let path = d.join("scene.ron");
    std::fs::write(&path, "previous").unwrap();
    // A directory in the way of the rename: the write succeeds, the rename fails.
    let blocked = d.join("blocked.ron");
    std::fs::create_dir(&blocked).unwrap();
    std::fs::write(blocked.join("keep"), "x").unwrap();
    assert!(app::formats::save(&scene, &blocked).is_err());
    assert!(blocked.join("keep").exists());
    assert!(app::formats::save(&scene, &d.join("missing/scene.ron")).is_err());
    assert_eq!(std::fs::read_to_string(&path).unwrap(), "previous");
    let leftovers: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(leftovers.len(), 2, "no temporary files left: {leftovers:?}");
}

#[test]
fn a_scene_of_objects_survives_a_version_2_project_and_version_1_opens_as_one_object() {
    use brickmap::objects::{Axis, ObjectOp, ObjectTree, Orientation, Placement};
    let dir = scratch("objects-project");
    let park = assets().join("ogt_test_multiple_model_scene.vox");
    let first = vox::import_objects(&std::fs::read(&park).unwrap(), &park, 2).unwrap();
    let table = first.scene.world.materials().clone();
    // Turn, hide and lock a few objects so every field travels.
    let nodes = first
        .scene
        .objects()
        .tree()
        .subtree(ObjectTree::ROOT)
        .unwrap();
    let (a, b, c) = (nodes[1], nodes[2], nodes[nodes.len() - 1]);
    let p = first.scene.objects().tree().node(a).unwrap().placement;
    let turned = Placement {
        rot: Orientation::quarter_turn(Axis::Y, 1).after(&p.rot),
        t: p.t,
    };
    for op in [
        ObjectOp::Place {
            node: a,
            placement: turned,
        },
        ObjectOp::Show {
            node: b,
            visible: false,
        },
        ObjectOp::Lock {
            node: c,
            locked: true,
        },
    ] {
        first.scene.apply(op).unwrap();
    }
    let file = dir.join("park.ron");
    project::save(&first.scene, &file).unwrap();
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(text.contains("format_version: 2,"), "{}", &text[..200]);
    let scene = project::load(&file, 2).unwrap();
    let (objects, first_objects) = (scene.objects(), first.scene.objects());
    assert_eq!(
        outline(&objects, &scene.world.materials()),
        outline(&first_objects, &table)
    );
    assert_eq!(objects.tree().layers(), first_objects.tree().layers());
    assert!(objects.tree().node(c).unwrap().locked);
    drop((objects, first_objects));
    assert_eq!(resolved(&scene.world), resolved(&first.scene.world));
    assert_eq!(scene.params, first.scene.params);
    // Saved again, the same text.
    assert_eq!(project::to_string(&scene), text);
    // One grid (version 1) is one object placing all of it.
    let flat = default_scene(SceneSize::Small, 2).unwrap();
    let v1 = dir.join("flat.ron");
    std::fs::write(&v1, project::grid_to_string(&flat)).unwrap();
    let one = project::load(&v1, 2).unwrap();
    let objects = one.objects();
    assert_eq!(objects.tree().len(), 2, "the root and the object");
    assert_eq!(objects.tree().drawn().len(), 1);
    assert_eq!(one.active(), Some(objects.tree().drawn()[0].node));
    assert_eq!(
        one.world.read().content_hash(),
        flat.world.read().content_hash()
    );
}

#[test]
fn hostile_version_2_projects_are_clear_errors() {
    let park = assets().join("ogt_test_multiple_model_scene.vox");
    let import = vox::import_objects(&std::fs::read(&park).unwrap(), &park, 1).unwrap();
    let text = project::to_string(&import.scene);
    assert!(import.scene.objects().tree().len() >= 2);
    let p = Path::new("hostile.ron");
    let err = |t: &str| {
        project::from_bytes(t.as_bytes(), p, 1)
            .map(|_| ())
            .unwrap_err()
            .to_string()
    };
    for (bad, want) in [
        (
            text.replacen("(parent: Some(0)", "(parent: Some(5)", 1),
            "does not come before it",
        ),
        (
            text.replacen("(parent: Some(0)", "(parent: None", 1),
            "only node 0 has no parent",
        ),
        (
            text.replacen("(parent: None", "(parent: Some(0)", 1),
            "node 0 must be the root group",
        ),
        (
            text.replacen("placement: (rot: 4,", "placement: (rot: 3,", 1),
            "rotation byte",
        ),
        (
            text.replacen("object: Some((model: ", "object: Some((model: 9", 1),
            "does not exist",
        ),
        (
            text.replacen("layers: [", "layers: [(name: \"x\", visible: true), ", 1)
                .replacen("layer: 0", "layer: 77", 1),
            "no layer 77",
        ),
        (text.replacen("size: (", "size: (-", 1), "model"),
        (text.replacen("data: \"VlhCMQ", "data: \"VlhCMg", 1), "VXB1"),
    ] {
        let e = err(&bad);
        assert!(e.contains(want), "want {want:?} in: {e}");
    }
    let far = {
        let key = "placement: (rot: 4, t: (";
        let at = text.find(key).unwrap() + key.len();
        let end = at + text[at..].find(',').unwrap();
        format!("{}2000000000{}", &text[..at], &text[end..])
    };
    let e = err(&far);
    assert!(e.contains("beyond ±1048576"), "{e}");
    // Every truncation fails cleanly (sampled); bytes changed at random give an error or a
    // scene, never a panic.
    for cut in (0..text.trim_end().len()).step_by(211) {
        assert!(project::from_bytes(&text.as_bytes()[..cut], p, 1).is_err());
    }
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for _ in 0..200 {
        let mut bytes = text.as_bytes().to_vec();
        for _ in 0..3 {
            let at = (next() % bytes.len() as u64) as usize;
            bytes[at] = b"0123456789-(),:[] aeSomeNn\"#"[(next() % 28) as usize];
        }
        let _ = project::from_bytes(&bytes, p, 1);
    }
}
