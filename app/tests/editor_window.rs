//! The real editor binary in a real window: under Xvfb on the machine's Vulkan driver
//! (lavapipe in CI) with the validation layer, `voxbrick --script` runs a replay script's
//! steps through the live editor, captures the presented frame (read back from the swapchain
//! image) and exits. The capture must equal a headless render of the saved state within
//! sampling noise, the run must report no validation error, and a screenshot of the screen
//! (xwd) must show a window that is not blank. Without Xvfb/xwd or a Vulkan driver the test
//! skips, saying so, unless VOXBRICK_REQUIRE_GPU=1 (CI) makes that a failure.

mod window;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use window::{Xvfb, have, no_vulkan, read_png, scratch, skip};

const SIZE: (u32, u32) = (160, 96);
const SPP: u32 = 16;

fn rms(a: &[u8], b: &[u8]) -> f64 {
    assert_eq!(a.len(), b.len());
    let sum: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (*x as f64 - *y as f64).powi(2))
        .sum();
    (sum / a.len() as f64).sqrt()
}

/// Distinct colours of an XWD screenshot's pixels inside `w`×`h` at the top left (a
/// 32-bit TrueColor dump, as Xvfb at depth 24 writes).
fn xwd_colours(bytes: &[u8], w: u32, h: u32) -> usize {
    let word = |i: usize| u32::from_be_bytes(bytes[4 * i..4 * i + 4].try_into().unwrap());
    let (header, width, height, bpp, line, ncolours) = (
        word(0) as usize,
        word(4),
        word(5),
        word(11),
        word(12) as usize,
        word(19) as usize,
    );
    assert_eq!(bpp, 32, "32-bit pixels");
    let start = header + 12 * ncolours;
    let mut seen = std::collections::HashSet::new();
    for y in 0..h.min(height) as usize {
        for x in 0..w.min(width) as usize {
            let p = start + y * line + 4 * x;
            seen.insert(&bytes[p..p + 3]);
        }
    }
    seen.len()
}

#[test]
fn the_live_editor_presents_what_a_headless_render_of_the_same_state_shows() {
    if !have("Xvfb") || !have("xwd") {
        return skip("Xvfb or xwd is not installed (packages xvfb, x11-apps)");
    }
    let Some(x) = Xvfb::start() else {
        return skip("Xvfb did not start");
    };
    let dir = scratch("live");
    let script =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/scripts/editor/live_viewport.ron");
    let capture = dir.join("capture.png");
    let mut editor = Command::new(env!("CARGO_BIN_EXE_voxbrick"))
        .arg("--script")
        .arg(&script)
        .arg("--capture")
        .arg(&capture)
        .args([
            "--capture-spp",
            &SPP.to_string(),
            "--window",
            &format!("{}x{}", SIZE.0, SIZE.1),
            "--validation",
            "--linger-ms",
            "4000",
        ])
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .env("VOXBRICK_CONFIG_DIR", dir.join("config"))
        .env("VOXBRICK_REPORT", dir.join("report.log"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("voxbrick starts");
    let mut report = window::Report::new(dir.join("report.log"));
    // While the window lingers after the capture, photograph the screen once a frame with
    // the panels is shown again.
    let started = Instant::now();
    let mut screenshot = None;
    while started.elapsed() < Duration::from_secs(600) {
        if let Ok(Some(_)) = editor.try_wait() {
            break;
        }
        if capture.exists() && screenshot.is_none() {
            report.skip_past();
            report.frame();
            let shot = Command::new("xwd")
                .args(["-root", "-silent", "-display", &x.display])
                .output()
                .expect("xwd runs");
            assert!(
                shot.status.success(),
                "xwd: {}",
                String::from_utf8_lossy(&shot.stderr)
            );
            screenshot = Some(shot.stdout);
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = editor.wait_with_output().unwrap();
    if no_vulkan(&out) {
        return skip(&format!(
            "no Vulkan device can draw a window: {}",
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "the editor failed: {}\n{}",
        String::from_utf8_lossy(&out.stdout),
        stderr
    );
    assert!(
        !stderr.contains("vulkan ERROR"),
        "validation errors:\n{stderr}"
    );
    // The window is on screen and shows more than a flat colour.
    let shot = screenshot.expect("a screenshot was taken while the window lingered");
    let colours = xwd_colours(&shot, SIZE.0, SIZE.1);
    assert!(colours > 50, "the window looks blank: {colours} colours");

    // The headless render of the same state, same seed and samples, and one with another
    // seed for the noise level.
    let state = dir.join("state.ron");
    assert!(
        state.exists(),
        "the script saved its state beside the capture"
    );
    let render = |seed: u64, out: &Path| {
        let r = Command::new(env!("CARGO_BIN_EXE_voxbrick"))
            .arg("render")
            .arg(&state)
            .arg("--out")
            .arg(out)
            .args([
                "--width",
                &SIZE.0.to_string(),
                "--height",
                &SIZE.1.to_string(),
                "--spp",
                &SPP.to_string(),
                "--seed",
                &seed.to_string(),
            ])
            .output()
            .unwrap();
        assert!(
            r.status.success(),
            "render: {}",
            String::from_utf8_lossy(&r.stderr)
        );
    };
    let (same, other) = (dir.join("same.png"), dir.join("other.png"));
    render(1, &same);
    render(2, &other);
    let (cw, ch, live) = read_png(&capture);
    assert_eq!((cw, ch), SIZE, "the capture has the window's size");
    let (_, _, headless) = read_png(&same);
    let (_, _, noise) = read_png(&other);
    let (diff, sampling) = (rms(&live, &headless), rms(&headless, &noise));
    eprintln!("live vs headless RMS {diff:.3} (8-bit units); two seeds {sampling:.3}");
    assert!(
        sampling > 1.0,
        "the seeds give different noise ({sampling})"
    );
    assert!(
        diff < 0.25 * sampling + 1.0,
        "the viewport differs from the headless render by more than rounding: RMS {diff:.3}, sampling noise {sampling:.3}"
    );
    // Red and blue in place: the capture's mean colour is the headless one's.
    let mean = |p: &[u8], c: usize| {
        p.iter().skip(c).step_by(3).map(|v| *v as f64).sum::<f64>() / (p.len() / 3) as f64
    };
    for c in 0..3 {
        assert!(
            (mean(&live, c) - mean(&headless, c)).abs() < 1.0,
            "channel {c}"
        );
    }
    assert!(
        (mean(&headless, 0) - mean(&headless, 2)).abs() > 2.0,
        "the scene is not grey"
    );
}

/// The editor's frame loop on the built-in default scene in a full-HD window with the
/// validation layer: no message at all (warnings included), with the device's own limits and
/// with them capped to 16 MiB of storage range and 64 MiB per allocation (the sized-down
/// paths: the shadow-ray queue, one world buffer per region, a smaller internal image). At
/// 1280 × 720 the shadow-ray queue once passed lavapipe's 128 MiB range (12 validation
/// errors per session).
#[test]
fn the_default_scene_in_a_full_hd_window_stays_within_the_device_limits() {
    if !have("Xvfb") {
        return skip("Xvfb is not installed (package xvfb)");
    }
    let Some(x) = Xvfb::start_sized("1920x1080") else {
        return skip("Xvfb did not start");
    };
    let dir = scratch("full-hd");
    let script = dir.join("default.ron");
    std::fs::write(
        &script,
        r#"(format_version: 1, start: Default, steps: [
            Do(Stroke((mode: Attach, shape: Sphere, size: 6.0, material: 0, points: [(256.0, 226.0, 256.0), (300.0, 226.0, 280.0)]))),
        ])"#,
    )
    .unwrap();
    for caps in [None, Some(("16M", "64M"))] {
        let capture = dir.join("capture.png");
        let _ = std::fs::remove_file(&capture);
        let mut command = Command::new(env!("CARGO_BIN_EXE_voxbrick"));
        command
            .arg("--script")
            .arg(&script)
            .arg("--capture")
            .arg(&capture)
            .args([
                "--capture-spp",
                "2",
                "--window",
                "1920x1080",
                "--validation",
            ])
            .env("DISPLAY", &x.display)
            .env_remove("WAYLAND_DISPLAY")
            .env_remove("VOXBRICK_MAX_STORAGE_RANGE")
            .env_remove("VOXBRICK_MAX_ALLOCATION")
            .env("VOXBRICK_CONFIG_DIR", dir.join("config"));
        if let Some((range, allocation)) = caps {
            command
                .env("VOXBRICK_MAX_STORAGE_RANGE", range)
                .env("VOXBRICK_MAX_ALLOCATION", allocation);
        }
        let out = command.output().unwrap();
        if no_vulkan(&out) {
            return skip(&format!(
                "no Vulkan device can draw a window: {}",
                String::from_utf8_lossy(&out.stderr).trim()
            ));
        }
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            out.status.success(),
            "caps {caps:?}: the editor failed: {stderr}"
        );
        assert!(
            !stderr.contains("vulkan "),
            "caps {caps:?}: validation messages:\n{stderr}"
        );
        let (w, h, _) = read_png(&capture);
        assert_eq!((w, h), (1920, 1080), "caps {caps:?}");
    }
}

#[test]
fn without_a_display_the_editor_says_so_in_one_line() {
    let config = scratch("nodisplay");
    let out = Command::new(env!("CARGO_BIN_EXE_voxbrick"))
        .args(["--window", "160x96"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env("VOXBRICK_CONFIG_DIR", config.path())
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    assert!(err.contains("display"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn a_failing_script_step_in_the_live_editor_exits_non_zero_naming_the_step() {
    if !have("Xvfb") {
        return skip("Xvfb is not installed (package xvfb)");
    }
    let Some(x) = Xvfb::start() else {
        return skip("Xvfb did not start");
    };
    let dir = scratch("failing");
    let script = dir.join("fails.ron");
    std::fs::write(
        &script,
        r#"(format_version: 1, start: New(size: (16, 16, 16)), steps: [
            Do(Stroke((mode: Attach, shape: Cube, size: 3.0, material: 0, points: [(8.0, 8.0, 8.0)]))),
            ExpectSolidCount(1),
        ])"#,
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_voxbrick"))
        .arg("--script")
        .arg(&script)
        .arg("--capture")
        .arg(dir.join("never.png"))
        .args(["--window", "96x64"])
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .env("VOXBRICK_CONFIG_DIR", dir.join("config"))
        .output()
        .unwrap();
    if no_vulkan(&out) {
        return skip(&format!(
            "no Vulkan device can draw a window: {}",
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "a failed step must fail the run");
    assert!(stderr.contains("step 2 (ExpectSolidCount)"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(
        !dir.join("never.png").exists(),
        "nothing captured after a failure"
    );
}

#[test]
fn a_gpu_failure_mid_session_keeps_the_unsaved_work_in_the_recovery_file() {
    if !have("Xvfb") {
        return skip("Xvfb is not installed (package xvfb)");
    }
    let Some(x) = Xvfb::start() else {
        return skip("Xvfb did not start");
    };
    let dir = scratch("gpu-failure");
    let script = dir.join("edits.ron");
    let last = r#"Stroke((mode: Attach, shape: Sphere, size: 4.0, material: 0, points: [(8.0, 10.0, 8.0)]))"#;
    std::fs::write(
        &script,
        format!(
            r#"(format_version: 1, start: New(size: (16, 16, 16)), steps: [
            Do(Stroke((mode: Attach, shape: Box, size: 1.0, material: 0, points: [(0.0, 0.0, 0.0), (15.0, 2.0, 15.0)]))),
            Save("saved.ron"),
            Do({last}),
        ])"#
        ),
    )
    .unwrap();
    // The steps run in the first frames; the device is "lost" at frame 40, long before the
    // (unreachable) capture.
    let out = Command::new(env!("CARGO_BIN_EXE_voxbrick"))
        .arg("--script")
        .arg(&script)
        .arg("--capture")
        .arg(dir.join("never.png"))
        .args(["--capture-spp", "100000", "--window", "96x64"])
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .env("VOXBRICK_CONFIG_DIR", dir.join("config"))
        .env("VOXBRICK_TEST_GPU_FAILURE_AT_FRAME", "40")
        .output()
        .unwrap();
    if no_vulkan(&out) {
        return skip(&format!(
            "no Vulkan device can draw a window: {}",
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "a GPU failure fails the run");
    assert!(
        stderr.contains("the GPU failed") && stderr.contains("device has been lost"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    // The recovery file holds the edit made after the save, exactly.
    let recovery = dir.join("config").join("recovery.ron");
    assert!(recovery.exists(), "{stderr}");
    let recovered = app::formats::load(&recovery, 1).unwrap();
    let mut expected = app::formats::load(&dir.join("saved.ron"), 1).unwrap();
    let hash = |s: &app::Scene| s.world.read().content_hash();
    assert_ne!(hash(&recovered), hash(&expected));
    let command: app::editor::command::Command = ron::from_str(last).unwrap();
    command.apply(&mut expected, &dir).unwrap();
    assert_eq!(hash(&recovered), hash(&expected));
}
