//! Qubicle `.qb` files written by Qubicle and vengi (`assets/qb/`, see SOURCES.md): each
//! imports with its matrices as objects, the three-voxel file voxel by voxel; import →
//! export → import keeps every voxel, colour and matrix exactly; damaged and hostile files
//! (cuts at every length, thousands of deterministic byte mutations, huge sizes) give an
//! error naming the problem or a valid scene, never a panic.

use super::*;
use app::formats::qb;

fn files() -> Vec<PathBuf> {
    asset_files("qb", "qb", 5)
}

#[test]
fn qubicle_files_import_as_objects_and_round_trip_exactly() {
    let d = scratch("qubicle");
    for file in files() {
        let bytes = std::fs::read(&file).unwrap();
        let matrices = qb::parse(&bytes).unwrap();
        let (scene, report) = qb::import(&bytes, &file, 2).unwrap();
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        assert_eq!(report.matrices, matrices.len(), "{name}");
        let declared: usize = matrices.iter().map(|m| m.voxels.len()).sum();
        assert_eq!(report.voxels, declared as u64, "{name}");
        assert_eq!(
            scene.objects().tree().drawn().len(),
            matrices.len(),
            "{name}"
        );
        assert_eq!(report.merged_colours, 0, "{name}: at most 256 colours");
        scene.world.read().validate().unwrap();
        // Export and import again: the same voxels, colours and matrices.
        let out = d.join(&name);
        let written = qb::export(&scene, &out).unwrap();
        assert_eq!(written.voxels, report.voxels);
        let again_bytes = std::fs::read(&out).unwrap();
        let (again, _) = qb::import(&again_bytes, &out, 2).unwrap();
        assert_eq!(content(&again.world), content(&scene.world), "{name}");
        let key = |ms: Vec<qb::Matrix>| {
            let lo = ms.iter().map(|m| m.position).reduce(IVec3::min).unwrap();
            let mut v: Vec<_> = ms
                .into_iter()
                .map(|mut m| {
                    m.voxels.sort_by_key(|(p, _)| (p.x, p.y, p.z));
                    (m.name, m.size, m.position - lo, m.voxels)
                })
                .collect();
            v.sort_by(|a, b| {
                a.0.cmp(&b.0)
                    .then(format!("{:?}", a.2).cmp(&format!("{:?}", b.2)))
            });
            v
        };
        assert_eq!(
            key(qb::parse(&again_bytes).unwrap()),
            key(matrices),
            "{name}"
        );
    }
}

#[test]
fn the_three_voxel_file_holds_blue_green_red_along_x() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/qb/vengi_rgb_small.qb");
    let (scene, report) = qb::import(&std::fs::read(&file).unwrap(), &file, 1).unwrap();
    assert_eq!((report.matrices, report.voxels, report.colours), (1, 3, 3));
    let got: Vec<_> = resolved(&scene.world)
        .into_iter()
        .map(|(p, k, _, c)| (p, k, c))
        .collect();
    assert_eq!(
        got,
        vec![
            (IVec3::new(0, 0, 0), MaterialKind::Lambertian, [0, 0, 255]),
            (IVec3::new(1, 0, 0), MaterialKind::Lambertian, [0, 255, 0]),
            (IVec3::new(2, 0, 0), MaterialKind::Lambertian, [255, 0, 0]),
        ]
    );
}

#[test]
fn damaged_and_hostile_qubicle_files_are_refused_without_a_panic() {
    let path = Path::new("hostile.qb");
    for file in files() {
        let bytes = std::fs::read(&file).unwrap();
        // Every cut short of the end: an error that says so.
        for cut in (0..bytes.len()).step_by((bytes.len() / 97).max(1)) {
            let e = qb::import(&bytes[..cut], path, 1).map(|_| ()).unwrap_err();
            let text = e.to_string();
            assert!(
                text.contains("truncated")
                    || text.contains("no matrix")
                    || text.contains("runs past"),
                "cut at {cut} of {}: {text}",
                file.display()
            );
        }
        // Deterministic mutations: an error or a valid scene.
        for m in mutations(&bytes, 400, 0x9e37_79b9) {
            if let Ok((scene, report)) = qb::import(&m, path, 1) {
                let view = scene.world.read();
                view.validate().unwrap();
                assert_eq!(view.solid_count() > 0, report.voxels > 0);
            }
        }
    }
    // The fuzzer's find: a matrix at z = 2³¹ − 2 (its end overflowed i32).
    let far = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds/qb_import/far_position.qb");
    let e = qb::import(&std::fs::read(&far).unwrap(), &far, 1)
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(e.contains("beyond ±16777216 voxels"), "{e}");
    // A matrix of 4096³ declared in a small file.
    let mut huge = std::fs::read(files()[0].clone()).unwrap();
    let name_len = huge[24] as usize;
    for k in 0..3 {
        let at = 25 + name_len + 4 * k;
        huge[at..at + 4].copy_from_slice(&4096u32.to_le_bytes());
    }
    let e = qb::import(&huge, path, 1)
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("cells together") || e.contains("truncated"),
        "{e}"
    );
}

#[test]
fn exports_say_what_the_format_cannot_hold() {
    let d = scratch("qubicle-export");
    // The default scene has metal, glass and a lamp: written as their colours.
    let scene = default_scene(SceneSize::Small, 2).unwrap();
    let r = qb::export(&scene, &d.join("default.qb")).unwrap();
    assert!(r.as_colour >= 2, "{r:?}");
    assert_eq!(r.voxels, scene.world.read().solid_count());
    // The command line converts both ways.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_voxbrick"))
        .args(["convert"])
        .arg(d.join("default.qb"))
        .arg(d.join("back.ron"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let back = app::formats::load(&d.join("back.ron"), 1).unwrap();
    assert_eq!(back.world.read().solid_count(), r.voxels);
}
