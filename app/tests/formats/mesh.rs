//! Meshes out, checked by their real consumers: every glTF written passes the Khronos
//! glTF-Validator with no error, and trimesh loads the OBJ, glTF and PLY and finds the
//! scene's exposed-face area, its bounds and its colours per face — against a count made here
//! voxel by voxel. The per-face form is closed (every edge met by its reverse); merged
//! rectangles cover exactly the same faces. The tools come from `tests/tools/mesh_tools.sh`
//! (in `tests/tools/.mesh-tools`, or `$VOXBRICK_MESH_TOOLS`); without them the test skips,
//! saying so, unless VOXBRICK_REQUIRE_GPU=1 (CI) makes that a failure.

use super::*;
use app::formats::mesh::{self, MeshOptions};
use std::collections::HashMap;
use std::process::Command;

/// The tools' folder, if the tools are there.
pub(super) fn tools() -> Option<PathBuf> {
    let dir = std::env::var_os("VOXBRICK_MESH_TOOLS")
        .filter(|d| !d.is_empty())
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/tools/.mesh-tools")
        });
    let ok = dir.join("node_modules/gltf-validator").is_dir()
        && dir.join("venv/bin/python").exists()
        && Command::new("node").arg("--version").output().is_ok();
    if ok {
        return Some(dir);
    }
    let why = format!(
        "no mesh tools in {} (run tests/tools/mesh_tools.sh)",
        dir.display()
    );
    assert!(
        std::env::var("VOXBRICK_REQUIRE_GPU").as_deref() != Ok("1"),
        "{why}, and VOXBRICK_REQUIRE_GPU=1"
    );
    eprintln!("SKIPPED: {why}; VOXBRICK_REQUIRE_GPU=1 makes this a failure");
    None
}

pub(super) fn script(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/tools")
        .join(name)
}

/// The Khronos validator's error count for a .glb or .gltf.
fn validator_errors(tools: &Path, file: &Path) -> u64 {
    let out = Command::new("node")
        .arg(script("gltf_validate.js"))
        .arg(file)
        .env("NODE_PATH", tools.join("node_modules"))
        .output()
        .unwrap();
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "{e}: {}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        )
    });
    assert!(
        report["messages"].as_array().is_some_and(|m| m.is_empty())
            || report["errors"].as_u64() == Some(0),
        "{}: {report}",
        file.display()
    );
    report["errors"].as_u64().unwrap()
}

/// What trimesh finds: area, bounds, area per sRGB colour.
struct Found {
    area: f64,
    bounds: [[f64; 3]; 2],
    colours: Vec<([i64; 3], f64)>,
}

fn trimesh(tools: &Path, file: &Path) -> Found {
    let out = Command::new(tools.join("venv/bin/python"))
        .arg(script("mesh_check.py"))
        .arg(file)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "trimesh on {}: {}",
        file.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let b = |i: usize, k: usize| v["bounds"][i][k].as_f64().unwrap();
    Found {
        area: v["area"].as_f64().unwrap(),
        bounds: [[b(0, 0), b(0, 1), b(0, 2)], [b(1, 0), b(1, 1), b(1, 2)]],
        colours: v["colours"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| {
                let c = c.as_array().unwrap();
                (
                    [0, 1, 2].map(|k| c[k].as_i64().unwrap()),
                    c[3].as_f64().unwrap(),
                )
            })
            .collect(),
    }
}

/// Faces that show, counted voxel by voxel: per sRGB colour, and the occupied bounds.
fn reference(scene: &Scene) -> (HashMap<[u8; 3], u64>, (IVec3, IVec3)) {
    let view = scene.world.read();
    let table = view.materials();
    let clear = |m: u8| {
        table
            .get(m)
            .is_ok_and(|x| x.kind == MaterialKind::Dielectric)
    };
    let dims = view.dims().voxels();
    let mut faces: HashMap<[u8; 3], u64> = HashMap::new();
    let (mut lo, mut hi) = (IVec3::MAX, IVec3::MIN);
    for x in 0..dims.x {
        for y in 0..dims.y {
            for z in 0..dims.z {
                let v = IVec3::new(x, y, z);
                let Some(m) = view.voxel(v).unwrap() else {
                    continue;
                };
                lo = lo.min(v);
                hi = hi.max(v + 1);
                for f in brickmap::FACES {
                    let n = view.voxel(v + f).ok().flatten();
                    let shows = match n {
                        None => true,
                        Some(k) => clear(m) != clear(k) || (clear(m) && m != k),
                    };
                    if shows {
                        let c = table.colour(table.get(m).unwrap().colour);
                        *faces.entry(c).or_default() += 1;
                    }
                }
            }
        }
    }
    (faces, (lo, hi))
}

/// Every edge of the quads, each direction counted: a closed surface meets each edge as
/// often in one direction as in the other.
fn closed(quads: &[mesh::Quad]) -> bool {
    let mut edges: HashMap<(IVec3, IVec3), i64> = HashMap::new();
    for q in quads {
        for k in 0..4 {
            let (a, b) = (q.corners[k], q.corners[(k + 1) % 4]);
            if a.to_array() < b.to_array() {
                *edges.entry((a, b)).or_default() += 1;
            } else {
                *edges.entry((b, a)).or_default() -= 1;
            }
        }
    }
    edges.values().all(|n| *n == 0)
}

#[test]
fn meshes_pass_the_gltf_validator_and_trimesh_finds_the_scenes_faces_bounds_and_colours() {
    let Some(tools) = tools() else { return };
    let dir = scratch("mesh");
    // The small default scene: terrain, metal, glass (its faces against the terrain show),
    // a lamp.
    let scene = default_scene(SceneSize::Small, 2).unwrap();
    let (want, (lo, hi)) = reference(&scene);
    let total: u64 = want.values().sum();
    let size = 0.5;
    let mut triangles = Vec::new();
    for greedy in [true, false] {
        let options = MeshOptions {
            greedy,
            per_object: false,
            voxel_size: size,
            keep_transforms: false,
        };
        let built = mesh::build(&scene, &options);
        let quads = &built.parts[0].quads;
        let area: i64 = quads.iter().map(|q| q.area()).sum();
        assert_eq!(
            area as u64, total,
            "greedy {greedy}: the quads cover every face once"
        );
        if !greedy {
            assert_eq!(quads.len() as u64, total);
            assert!(closed(quads), "one quad per face is a closed surface");
        }
        triangles.push(quads.len() * 2);
        for ext in ["glb", "gltf", "obj", "ply"] {
            let file = dir.join(format!("scene-{greedy}.{ext}"));
            mesh::export(&scene, &file, &options).unwrap();
            if ext.starts_with("gl") {
                assert_eq!(validator_errors(&tools, &file), 0, "{}", file.display());
            }
            let found = trimesh(&tools, &file);
            let what = format!("{ext}, greedy {greedy}");
            let faces_area = total as f64 * size * size;
            assert!(
                (found.area - faces_area).abs() < 1e-6 * faces_area,
                "{what}: area {} ≠ {faces_area}",
                found.area
            );
            for k in 0..3 {
                assert_eq!(
                    found.bounds[0][k],
                    f64::from(lo[k]) * size,
                    "{what}: bounds"
                );
                assert_eq!(
                    found.bounds[1][k],
                    f64::from(hi[k]) * size,
                    "{what}: bounds"
                );
            }
            // Each colour's area, the file's colours matched to the table's within rounding
            // (glTF keeps linear factors).
            let mut got: HashMap<[u8; 3], f64> = HashMap::new();
            for (c, a) in &found.colours {
                let near = want
                    .keys()
                    .find(|w| (0..3).all(|k| (i64::from(w[k]) - c[k]).abs() <= 2))
                    .unwrap_or_else(|| panic!("{what}: colour {c:?} is no material's"));
                *got.entry(*near).or_default() += a;
            }
            for (c, n) in &want {
                let a = got.get(c).copied().unwrap_or(0.0);
                assert!(
                    (a - *n as f64 * size * size).abs() < 1e-6 * a.max(1.0),
                    "{what}: colour {c:?} covers {a}, not {}",
                    *n as f64 * size * size
                );
            }
        }
    }
    assert!(
        triangles[0] * 4 < triangles[1],
        "merging: {} triangles against {} one quad per face",
        triangles[0],
        triangles[1]
    );
    eprintln!(
        "small default scene: {} triangles merged, {} one per face",
        triangles[0], triangles[1]
    );
    // Per object: a MagicaVoxel scene of 104 objects in groups — a node per object, valid.
    let vox = app::formats::load(&assets().join("ogt_test_multiple_model_scene.vox"), 2).unwrap();
    let per_object = MeshOptions {
        per_object: true,
        ..MeshOptions::default()
    };
    let built = mesh::build(&vox, &per_object);
    assert_eq!(built.parts.len(), vox.objects().tree().drawn().len());
    for ext in ["glb", "gltf", "obj"] {
        let file = dir.join(format!("objects.{ext}"));
        let stats = mesh::export(&vox, &file, &per_object).unwrap();
        assert_eq!(stats.parts, built.parts.len());
        if ext.starts_with("gl") {
            assert_eq!(validator_errors(&tools, &file), 0);
        }
        let found = trimesh(&tools, &file);
        let area: i64 = built
            .parts
            .iter()
            .flat_map(|p| &p.quads)
            .map(|q| q.area())
            .sum();
        assert!(
            (found.area - area as f64).abs() < 1e-6 * found.area,
            "{ext}: area"
        );
    }
    // The placements kept as node matrices (the meshes in their own frames): valid, and
    // trimesh, applying the matrices, finds the same area and bounds as with them applied.
    let applied = trimesh(&tools, &dir.join("objects.glb"));
    let kept = MeshOptions {
        keep_transforms: true,
        ..per_object.clone()
    };
    let file = dir.join("kept.glb");
    mesh::export(&vox, &file, &kept).unwrap();
    assert_eq!(validator_errors(&tools, &file), 0);
    let found = trimesh(&tools, &file);
    assert!((found.area - applied.area).abs() < 1e-6 * found.area);
    assert_eq!(found.bounds, applied.bounds, "the same place in the world");
    let identity = [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
    let local = mesh::build(&vox, &kept);
    assert!(
        local
            .parts
            .iter()
            .any(|p| p.transform.is_some_and(|(r, _)| r != identity)),
        "some object of the sample is turned"
    );
    // Nothing to mesh, a bad size, an unknown extension: refused, nothing written.
    let empty = app::scene::Scene::empty(GridDims::new(2, 2, 2).unwrap(), 1).unwrap();
    assert!(mesh::export(&empty, &dir.join("e.glb"), &MeshOptions::default()).is_err());
    let bad = MeshOptions {
        voxel_size: 0.0,
        ..MeshOptions::default()
    };
    assert!(mesh::export(&scene, &dir.join("z.obj"), &bad).is_err());
    assert!(mesh::export(&scene, &dir.join("z.stl"), &MeshOptions::default()).is_err());
    for f in ["e.glb", "z.obj", "z.stl", "z.mtl"] {
        assert!(!dir.join(f).exists(), "{f} written");
    }
}

/// A long export reports its progress (never backwards, up to the file) and stops when
/// told to, writing nothing; a finished export after it is whole.
#[test]
fn a_mesh_export_reports_progress_and_a_cancel_writes_nothing() {
    let d = scratch("mesh-cancel");
    let scene = app::ui::files::new_scene((256, 64, 256), true, 2).unwrap();
    let out = d.join("terrain.glb");
    let seen = std::sync::Mutex::new(Vec::new());
    let options = MeshOptions::default();
    mesh::export_watched(&scene, &out, &options, &|f| {
        seen.lock().unwrap().push(f);
        true
    })
    .unwrap();
    let seen = seen.into_inner().unwrap();
    assert!(seen.len() >= 3, "{seen:?}");
    assert!(seen.windows(2).all(|w| w[0] <= w[1]), "{seen:?}");
    assert_eq!(*seen.last().unwrap(), 0.9);
    let whole = std::fs::read(&out).unwrap();
    std::fs::remove_file(&out).unwrap();
    for stop_at in [0, seen.len() - 1] {
        let calls = std::sync::atomic::AtomicUsize::new(0);
        let e = mesh::export_watched(&scene, &out, &options, &|_| {
            calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed) < stop_at
        })
        .unwrap_err();
        assert!(matches!(e, FormatError::Cancelled { .. }), "{e}");
        assert!(!out.exists(), "a cancelled export wrote {}", out.display());
    }
    mesh::export(&scene, &out, &options).unwrap();
    assert_eq!(std::fs::read(&out).unwrap(), whole);
}
