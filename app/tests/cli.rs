//! The `voxbrick` binary end to end: the main job's statistics, conversions, new terrain,
//! info, and one-line errors that leave files alone.

use std::path::Path;
use std::process::Command;

fn voxbrick(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_voxbrick"))
        .args(args)
        .output()
        .expect("voxbrick runs")
}

fn ok(args: &[&str]) -> String {
    let out = voxbrick(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// Runs voxbrick with a GPU command's arguments: its standard output when it succeeded, None
/// (saying so) when this machine has no Vulkan driver, unless VOXBRICK_REQUIRE_GPU=1 (CI)
/// makes that a failure; any other failure fails the test.
fn succeeds_on_gpu(args: &[&str]) -> Option<String> {
    let out = voxbrick(args);
    let err = String::from_utf8_lossy(&out.stderr);
    if !out.status.success()
        && err.contains("no usable Vulkan device")
        && std::env::var("VOXBRICK_REQUIRE_GPU").as_deref() != Ok("1")
    {
        eprintln!(
            "SKIPPED: no Vulkan driver on this machine; VOXBRICK_REQUIRE_GPU=1 makes this a failure"
        );
        return None;
    }
    assert!(out.status.success(), "{args:?}: {err}");
    Some(String::from_utf8_lossy(&out.stdout).into_owned())
}

fn fails(args: &[&str]) -> String {
    let out = voxbrick(args);
    assert!(!out.status.success(), "{args:?} succeeded");
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    err
}

fn field<'a>(out: &'a str, name: &str) -> &'a str {
    out.lines()
        .find(|l| l.starts_with(name))
        .unwrap_or_else(|| panic!("no {name} in:\n{out}"))
}

/// A scratch folder for this test, removed when it passes.
fn scratch(name: &str) -> app::scratch::Scratch {
    app::scratch::Scratch::new(&format!("cli-{name}"))
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn stats_reports_the_default_scene() {
    let text = ok(&["stats", "--size", "small", "--workers", "2"]);
    assert!(field(&text, "scene").contains("128 x 64 x 128 voxels"));
    let solid: u64 = field(&text, "solid")
        .split_whitespace()
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    assert!(
        solid > 128 * 128 * 16,
        "terrain is solid underground: {solid}"
    );
    assert!(
        field(&text, "materials")
            .contains("7 in the table (4 lambertian, 1 metal, 1 dielectric, 1 emissive)")
    );
    assert!(field(&text, "pick").contains("normal [0, 1, 0]"), "{text}");
    // The same scene with another worker count has the same content.
    let other = ok(&["stats", "--size", "small", "--workers", "1"]);
    assert_eq!(field(&text, "content hash"), field(&other, "content hash"));
}

#[test]
fn new_terrain_is_deterministic_and_converts_both_ways() {
    let d = scratch("terrain");
    let (a, b) = (d.join("a.ron"), d.join("b.ron"));
    let args = |p: &Path| {
        vec![
            "new",
            "--terrain",
            "--size",
            "96x48x64",
            "--seed",
            "9",
            "--water-level",
            "14",
            "--workers",
            "2",
            s(p),
        ]
        .into_iter()
        .map(String::from)
        .collect::<Vec<_>>()
    };
    ok(&args(&a).iter().map(String::as_str).collect::<Vec<_>>());
    let mut other = args(&b);
    other[9] = "1".into(); // another worker count
    ok(&other.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(
        std::fs::read(&a).unwrap(),
        std::fs::read(&b).unwrap(),
        "same parameters, same file, byte for byte"
    );
    let info = ok(&["info", s(&a)]);
    assert!(field(&info, "scene").contains("96 x 48 x 64 voxels"));
    assert!(
        field(&info, "materials").contains("1 dielectric"),
        "water: {info}"
    );
    // ron → vox → ron keeps the voxels (the grid is re-fitted to the content on import).
    let v = d.join("a.vox");
    ok(&["convert", s(&a), s(&v)]);
    let back = d.join("back.ron");
    ok(&["convert", s(&v), s(&back)]);
    let again = ok(&["info", s(&back)]);
    assert_eq!(field(&info, "solid"), field(&again, "solid"));
    // A grid is one object; a MagicaVoxel scene shows its objects.
    assert!(
        field(&info, "objects")
            .starts_with("objects      1 objects of 1 models (0 shared), 0 groups"),
        "{info}"
    );
    let ogt = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../assets/vox/ogt_test_multiple_model_scene.vox");
    let scene = ok(&["info", s(&ogt)]);
    assert!(
        field(&scene, "objects").contains("104 objects of 41 models (16 shared)"),
        "{scene}"
    );
    assert!(field(&scene, "objects").contains("8 layers"), "{scene}");
    // Its tree, a line per node, the same after a conversion to a project.
    let tree = |out: &str| -> Vec<String> {
        out.lines()
            .skip_while(|l| *l != "tree")
            .skip(1)
            .take_while(|l| l.starts_with("  "))
            .map(String::from)
            .collect()
    };
    let lines = tree(&scene);
    assert_eq!(lines.len(), 104, "{scene}");
    assert!(lines[0].starts_with("  #1 "), "{}", lines[0]);
    assert!(
        lines.iter().any(|l| l.contains(", placed by ")),
        "shared models are named: {scene}"
    );
    let project = d.join("ogt.ron");
    ok(&["convert", s(&ogt), s(&project)]);
    assert_eq!(tree(&ok(&["info", s(&project)])), lines);
    // --flatten: one object showing the same voxels, from the project and from the file.
    for from in [&project, &ogt] {
        let flat = d.join("flat.ron");
        ok(&["convert", "--flatten", s(from), s(&flat)]);
        let info = ok(&["info", s(&flat)]);
        assert!(
            field(&info, "objects").starts_with("objects      1 objects of 1 models"),
            "{info}"
        );
        assert_eq!(field(&info, "solid"), field(&scene, "solid"));
        assert_eq!(tree(&info).len(), 1);
    }
}

/// `new --terrain` and the load of what it wrote run on every worker with no per-voxel work
/// on their path: the grid becomes one object by a copy of each worker's slab (as many
/// threads as workers), no model brick is rewritten voxel by voxel and the composite
/// recomputes nothing (the regression that made a 4096 × 1024 × 4096 terrain 8× slower).
#[test]
fn new_terrain_and_its_load_use_every_worker_and_no_voxel_work() {
    let d = scratch("bulk");
    let a = d.join("a.ron");
    let out = voxbrick(&["new", "--terrain", "--size", "256x64x256", s(&a)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let expect = format!(
        "on {cores} workers (adopted as one object on {cores} threads; \
         0 bricks rewritten voxel by voxel, 0 composited, 0 undo records)"
    );
    assert!(err.contains(&expect), "expected `{expect}` in: {err}");
    let info = ok(&["info", s(&a)]);
    assert!(field(&info, "loaded").contains(&expect), "{info}");
    // A scene of several objects loads through the composite, and says so.
    let ogt = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../assets/vox/ogt_test_multiple_model_scene.vox");
    let p = d.join("ogt.ron");
    ok(&["convert", s(&ogt), s(&p)]);
    let info = ok(&["info", s(&p)]);
    assert!(
        !field(&info, "loaded").contains(" 0 composited,"),
        "objects are composited: {info}"
    );
}

#[test]
fn errors_are_one_clear_line_and_touch_nothing() {
    let d = scratch("errors");
    let target = d.join("keep.ron");
    std::fs::write(&target, "precious").unwrap();
    let err = fails(&["convert", "/no/such/file.vox", s(&target)]);
    assert!(err.contains("/no/such/file.vox"), "{err}");
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "precious");
    let bad = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/vox/dotvox_not_a.vox");
    let err = fails(&["convert", s(&bad), s(&target)]);
    assert!(err.contains("not a valid .vox"), "{err}");
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "precious");
    assert!(
        fails(&["info", s(&d.join("scene.txt"))]).contains("expected .ron, .vox, .qb or .schem")
    );
    assert!(fails(&["new", s(&d.join("x.ron"))]).contains("--terrain"));
    assert!(fails(&["new", "--terrain", "--size", "8x8", s(&d.join("x.ron"))]).contains("WxHxD"));
    assert!(
        fails(&[
            "new",
            "--terrain",
            "--size",
            "8000x8x8",
            s(&d.join("x.ron"))
        ])
        .contains("grid")
    );
    assert!(
        fails(&[
            "new",
            "--terrain",
            "--size",
            "64x32x64",
            "--height-min",
            "30",
            "--height-max",
            "20",
            s(&d.join("x.ron"))
        ])
        .contains("height range")
    );
    assert!(fails(&["stats", "--size", "huge"]).contains("invalid value 'huge'"));
    assert!(fails(&["stats", "--workers", "5000"]).contains("5000 workers"));
    assert!(!d.join("x.ron").exists());
}

#[test]
fn render_on_the_cpu_writes_png_and_pfm() {
    let d = scratch("render");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/vox/mmmm_chr_robot.vox");
    let (png, pfm) = (d.join("robot.png"), d.join("robot.pfm"));
    let small = |png: &Path, pfm: &Path, extra: &[&str]| {
        let mut args = vec!["render", s(&scene), "--out", s(png), "--hdr", s(pfm)];
        args.extend([
            "--device", "cpu", "--spp", "2", "--width", "40", "--height", "30",
        ]);
        ok(&[&args[..], extra].concat())
    };
    let text = small(&png, &pfm, &[]);
    assert!(field(&text, "rendered").contains("2400 samples"), "{text}");
    assert!(field(&text, "rays").contains("Mrays/s"));
    let png_bytes = std::fs::read(&png).unwrap();
    assert!(png_bytes.starts_with(b"\x89PNG"));
    let pfm_bytes = std::fs::read(&pfm).unwrap();
    assert!(pfm_bytes.starts_with(b"PF\n40 30\n"));
    assert_eq!(pfm_bytes.len(), b"PF\n40 30\n-1.0\n".len() + 40 * 30 * 12);
    // A device that does not exist is a clear error naming the fallback, never a silent one.
    let err = fails(&[
        "render",
        s(&scene),
        "--out",
        s(&d.join("x.png")),
        "--device",
        "no such gpu 9000",
    ]);
    assert!(err.contains("--device cpu"), "{err}");
    assert!(!d.join("x.png").exists());
    assert!(
        fails(&[
            "render",
            s(&scene),
            "--out",
            s(&png),
            "--device",
            "cpu",
            "--camera",
            "1,2:3"
        ])
        .contains("X,Y,Z")
    );
    // An orthographic render is a different image; a bad height is refused by name.
    let ortho = d.join("ortho.pfm");
    small(&d.join("ortho.png"), &ortho, &["--orthographic", "40"]);
    assert_ne!(std::fs::read(&ortho).unwrap(), pfm_bytes);
    let err = fails(&[
        "render",
        s(&scene),
        "--out",
        s(&d.join("y.png")),
        "--device",
        "cpu",
        "--orthographic",
        "0",
    ]);
    assert!(err.contains("orthographic height"), "{err}");
    assert!(!d.join("y.png").exists());
}

#[test]
fn stress_on_the_cpu_reference_writes_its_report() {
    let dir = scratch("stress");
    let out = ok(&[
        "stress",
        "--device",
        "cpu",
        "--cpu-size",
        "4",
        "--cpu-renders",
        "1",
        "--out",
        s(&dir),
    ]);
    // Only the CPU reference's images: no ray table, one row per scene, all clean.
    assert!(!out.contains("| world |"), "{out}");
    let rows: Vec<&str> = out.lines().filter(|l| l.contains("| CPU |")).collect();
    assert!(rows.len() >= 13, "{out}");
    assert!(rows.iter().all(|l| l.ends_with("| ok |")), "{out}");
    let json = std::fs::read_to_string(dir.join("stress.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(v["images"].as_array().unwrap().len(), rows.len());
    assert_eq!(
        v["images"][0]["samples"],
        2 * 16,
        "two views of 4 × 4 pixels"
    );
    assert_eq!(std::fs::read_to_string(dir.join("stress.md")).unwrap(), out);
    fails(&["stress", "--rays", "-3"]);
}

#[test]
fn bench_plays_the_path_and_writes_its_report() {
    let dir = scratch("bench");
    if succeeds_on_gpu(&[
        "bench",
        "--sizes",
        "32x18",
        "--frames",
        "3",
        "--repeat",
        "1",
        "--presets",
        "complexity-1,physical",
        "--cpu-size",
        "8x4",
        "--cpu-frames",
        "2",
        "--edit-radii",
        "16",
        "--edit-frames",
        "2",
        "--view-size",
        "16x9",
        "--view-spp",
        "1",
        "--out",
        s(&dir),
    ])
    .is_none()
    {
        return;
    }
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("bench.json")).unwrap()).unwrap();
    let gpu = v["gpu"].as_array().unwrap();
    assert_eq!(gpu.len(), 2, "two presets at one size");
    for g in gpu {
        let ms = g["frame_ms"].as_array().unwrap();
        assert_eq!(ms.len(), 3);
        assert!(ms.iter().all(|m| m.as_f64().unwrap() > 0.0));
        assert_eq!(
            g["path_time_s"][2], 20.0,
            "the last frame is the path's end"
        );
        assert!(g["rays_per_pixel"]["primary"].as_f64().unwrap() >= 1.0);
    }
    // Physical traces more rays per pixel than complexity 1.
    assert!(
        gpu[1]["rays_per_pixel"]["all"].as_f64().unwrap()
            > gpu[0]["rays_per_pixel"]["all"].as_f64().unwrap()
    );
    assert_eq!(v["cpu"].as_array().unwrap().len(), 2);
    let edit = &v["editing"][0];
    assert_eq!(edit["edits"], 2);
    assert!(
        edit["uploaded_bytes_per_edit"]["min"].as_f64().unwrap() > 0.0,
        "each edit uploads"
    );
    for f in [
        "bench.md",
        "frame_time_32x18.png",
        "frame_time_cpu.png",
        "views/t00.0s.png",
        "views/t20.0s.png",
    ] {
        assert!(dir.join(f).is_file(), "{f}");
    }
    let png = std::fs::read(dir.join("frame_time_32x18.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    // Bad arguments: one line, nothing written.
    let bad = scratch("bench-bad");
    fails(&["bench", "--sizes", "0x5", "--out", s(&bad)]);
    fails(&["bench", "--presets", "complexity-9", "--out", s(&bad)]);
    fails(&["bench", "--path", "/no/such/path.ron", "--out", s(&bad)]);
    assert_eq!(std::fs::read_dir(&bad).unwrap().count(), 0);
}

#[test]
fn bench_error_measures_every_choice_against_a_checked_reference() {
    let dir = scratch("bench-error");
    if succeeds_on_gpu(&[
        "bench-error",
        "--size",
        "32x18",
        "--reference-spp",
        "256",
        "--max-spp",
        "8",
        "--views",
        "0",
        "--presets",
        "lamps",
        "--out",
        s(&dir),
    ])
    .is_none()
    {
        return;
    }
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("error.json")).unwrap()).unwrap();
    let cases = v["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 1);
    assert_eq!(cases[0]["name"], "physical + lamps");
    let view = &cases[0]["views"][0];
    assert!(view["reference_noise"].as_f64().unwrap() > 0.0);
    let curves = view["curves"].as_array().unwrap();
    let named = |n: &str| {
        curves
            .iter()
            .find(|c| c["name"] == n)
            .unwrap_or_else(|| panic!("no curve {n}"))
    };
    for c in curves {
        let spp: Vec<u64> = c["levels"]
            .as_array()
            .unwrap()
            .iter()
            .map(|l| l["spp"].as_u64().unwrap())
            .collect();
        assert_eq!(spp, [1, 2, 4, 8], "{}", c["name"]);
        assert!(c["ms_per_sample"].as_f64().unwrap() > 0.0);
        assert_eq!(c["passed"], true, "{}", c["name"]);
        // Choices that only schedule samples otherwise render the defaults' image.
        if let Some(same) = c["same_image_rel_mse"].as_f64() {
            assert!(same < 1e-10, "{}: {same}", c["name"]);
        }
    }
    let rel = |c: &serde_json::Value, i: usize| c["levels"][i]["rel_mse"].as_f64().unwrap();
    for n in ["defaults", "independent numbers", "no light sampling"] {
        let c = named(n);
        assert!(c["same_image_rel_mse"].is_null(), "{n} has its own curve");
        assert!(
            rel(c, 3) < rel(c, 0) / 4.0,
            "{n}: the error falls with samples"
        );
    }
    // The denoiser: measured (not checked: biased), its filter timed, the noise it removes
    // at 1 spp worth more than its bias.
    let denoised = named("denoised (viewport)");
    assert!(denoised["same_image_rel_mse"].is_null());
    for l in denoised["levels"].as_array().unwrap() {
        assert!(l["filter_ms"].as_f64().unwrap() > 0.0);
    }
    assert!(rel(denoised, 0) < rel(named("defaults"), 0));
    // Without the fade: up to 8 spp (where the fade starts) the same image, up to the order
    // of the float atomics that sum sliced samples.
    let unfaded = named("denoised, no fade");
    for i in 0..4 {
        let (a, b) = (rel(unfaded, i), rel(denoised, i));
        assert!((a - b).abs() <= 1e-3 * b, "level {i}: {a} vs {b}");
    }
    // Light sampling and Sobol numbers beat BSDF sampling and independent numbers at 8 spp.
    assert!(rel(named("defaults"), 3) < rel(named("independent numbers"), 3));
    assert!(rel(named("defaults"), 3) < rel(named("no light sampling"), 3));
    let csv = std::fs::read_to_string(dir.join("error.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 4 * curves.len());
    let md = std::fs::read_to_string(dir.join("error.md")).unwrap();
    assert!(md.contains("Denoised (viewport)"), "{md}");
    // Each denoised choice's table is headed by its own name.
    assert!(
        md.contains("\nDenoised, no fade: the defaults' relMSE"),
        "{md}"
    );
    for f in [
        "error.md",
        "relmse_spp_physical___lamps.png",
        "relmse_time_physical___lamps.png",
        "flip_spp_physical___lamps.png",
        "reference_physical___lamps_t00.0s.png",
    ] {
        assert!(dir.join(f).is_file(), "{f}");
    }
    // Bad arguments: one line, nothing written.
    let bad = scratch("bench-error-bad");
    fails(&["bench-error", "--max-spp", "6", "--out", s(&bad)]);
    fails(&[
        "bench-error",
        "--max-spp",
        "8",
        "--reference-spp",
        "32",
        "--out",
        s(&bad),
    ]);
    fails(&["bench-error", "--views", "99", "--out", s(&bad)]);
    fails(&["bench-error", "--presets", "nope", "--out", s(&bad)]);
    fails(&[
        "bench-error",
        "--choices",
        "denoised,nope",
        "--out",
        s(&bad),
    ]);
    fails(&[
        "bench-error",
        "--reference-sequence",
        "halton",
        "--out",
        s(&bad),
    ]);
    assert_eq!(std::fs::read_dir(&bad).unwrap().count(), 0);
}

#[test]
fn bench_skips_measures_each_skip_on_two_scenes() {
    let dir = scratch("bench-skips");
    if succeeds_on_gpu(&[
        "bench-skips",
        "--size",
        "32x18",
        "--window",
        "64x36",
        "--rounds",
        "1",
        "--reference-seconds",
        "8",
        "--out",
        s(&dir),
    ])
    .is_none()
    {
        return;
    }
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("skips.json")).unwrap()).unwrap();
    let rows = v["rows"].as_array().unwrap();
    // Seven skips, each on the benchmark scene and on one that needs it.
    assert_eq!(rows.len(), 14);
    for pair in rows.chunks(2) {
        assert_eq!(pair[0]["skip"], pair[1]["skip"]);
        assert!(pair[0]["scene"].as_str().unwrap().starts_with("thesis"));
        assert_ne!(pair[0]["scene"], pair[1]["scene"]);
    }
    for r in rows {
        for k in ["with", "without", "gain"] {
            let x = r[k].as_f64().unwrap();
            assert!(x.is_finite() && x > 0.0, "{}: {k} {x}", r["name"]);
        }
        // A traversal or pipeline skip changes the time, never the image.
        if let Some(same) = r["same_image_rel_mse"].as_f64() {
            assert!(same < 1e-8, "{}: {same}", r["name"]);
        }
        // A second of accumulated frames: far less error than one frame's samples.
        if r["skip"] == "Accumulation" {
            assert!(r["gain"].as_f64().unwrap() > 10.0, "{r}");
        }
    }
    let md = std::fs::read_to_string(dir.join("skips.md")).unwrap();
    assert_eq!(md.lines().filter(|l| l.starts_with("| ")).count(), 15);
    let bad = scratch("bench-skips-bad");
    fails(&["bench-skips", "--size", "0x5", "--out", s(&bad)]);
    fails(&["bench-skips", "--window", "big", "--out", s(&bad)]);
    assert_eq!(std::fs::read_dir(&bad).unwrap().count(), 0);
}

#[test]
fn bench_viewport_times_the_frames_with_the_denoiser_too() {
    let args = [
        "bench-viewport",
        "--size",
        "64x64",
        "--scales",
        "1.0",
        "--frames",
        "4",
        "--denoise",
    ];
    let Some(text) = succeeds_on_gpu(&args) else {
        return;
    };
    for case in [
        "refining (still camera)",
        "camera moving",
        "refining, denoised",
        "moving, denoised",
    ] {
        let line = text
            .lines()
            .find(|l| l.contains(case))
            .unwrap_or_else(|| panic!("no {case}: {text}"));
        // min / median / p99 / max GPU ms, each a positive number.
        let times: Vec<f64> = line
            .split_whitespace()
            .filter_map(|w| w.parse().ok())
            .collect();
        assert!(
            times.len() >= 5 && times[..5].iter().all(|t| *t > 0.0),
            "{line}"
        );
    }
}

#[test]
fn bench_gpu_times_a_scene_file_per_sample() {
    let dir = scratch("bench-gpu-scene");
    let file = dir.join("terrain.ron");
    ok(&["new", "--terrain", "--size", "32x16x32", s(&file)]);
    let Some(out) = succeeds_on_gpu(&[
        "bench-gpu",
        "--scene",
        s(&file),
        "--bounces",
        "2",
        "--width",
        "32",
        "--height",
        "18",
        "--frames",
        "10",
        "--spp",
        "2",
    ]) else {
        return;
    };
    assert!(out.contains("32x18, 2 bounces"), "{out}");
    assert!(out.contains("dispatches of 2 spp"), "{out}");
    let median: f64 = field(&out, "per sample")
        .split_whitespace()
        .nth(3)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{out}"));
    assert!(median > 0.0, "{out}");
    assert!(field(&out, "per sample").contains("10 dispatches"), "{out}");
    // 576 camera rays a sample, counted.
    assert!(field(&out, "rays").contains("0.00 M camera"), "{out}");
    let busy: f64 = field(&out, "lanes busy")
        .split_whitespace()
        .nth(2)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{out}"));
    assert!(busy > 0.0 && busy <= 100.0, "{out}");
    fails(&["bench-gpu", "--scene", s(&dir.join("missing.ron"))]);
    fails(&["bench-gpu", "--scene", s(&file), "--bounces", "99"]);
    fails(&["bench-gpu", "--bounces", "3"]);
    fails(&["bench-gpu", "--spp", "2"]);
    fails(&["bench-gpu", "--scene", s(&file), "--spp", "0"]);
    fails(&["bench-gpu", "--scene", s(&file), "--spp", "17"]);
    fails(&["bench-error", "--choices", "denoised-fade-64-8"]);
}
