//! The real editor binary in a real window: under Xvfb on the machine's Vulkan driver
//! (lavapipe in CI) with the validation layer, `voxbrick --script` runs a replay script's
//! steps through the live editor, captures the presented frame (read back from the swapchain
//! image) and exits. The capture must equal a headless render of the saved state within
//! sampling noise, the run must report no validation error, and a screenshot of the screen
//! (xwd) must show a window that is not blank. Without Xvfb/xwd or a Vulkan driver the test
//! skips, saying so, unless VOXBRICK_REQUIRE_GPU=1 (CI) makes that a failure.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const SIZE: (u32, u32) = (160, 96);
const SPP: u32 = 16;

fn require() -> bool {
    std::env::var("VOXBRICK_REQUIRE_GPU").as_deref() == Ok("1")
}

fn skip(why: &str) {
    assert!(!require(), "{why}, and VOXBRICK_REQUIRE_GPU=1");
    eprintln!("SKIPPED: {why}; VOXBRICK_REQUIRE_GPU=1 makes this a failure");
}

/// The editor exited because this machine has no Vulkan device that can draw a window.
fn no_vulkan(out: &std::process::Output) -> bool {
    let stderr = String::from_utf8_lossy(&out.stderr);
    !out.status.success()
        && (stderr.contains("no usable Vulkan") || stderr.contains("no Vulkan device"))
}

fn have(tool: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {tool}")])
        .stdout(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// An Xvfb server of our own, killed on drop.
struct Xvfb {
    child: Child,
    display: String,
}

impl Xvfb {
    fn start() -> Option<Self> {
        Self::start_sized("320x240")
    }

    fn start_sized(size: &str) -> Option<Self> {
        // Tests of this file run in parallel: each takes its own number, and a server that
        // lost the race for a number (it exits at once) makes it try the next.
        static NEXT: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        for _ in 0..20 {
            let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            let number = 90 + (std::process::id() * 7 + n) % 400;
            if Path::new(&format!("/tmp/.X11-unix/X{number}")).exists()
                || Path::new(&format!("/tmp/.X{number}-lock")).exists()
            {
                continue;
            }
            let display = format!(":{number}");
            let child = Command::new("Xvfb")
                .args([
                    &display,
                    "-screen",
                    "0",
                    &format!("{size}x24"),
                    "-nolisten",
                    "tcp",
                ])
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .ok()?;
            let mut x = Xvfb { child, display };
            let socket = format!("/tmp/.X11-unix/X{number}");
            let started = Instant::now();
            while started.elapsed() < Duration::from_secs(10) {
                if Path::new(&socket).exists() {
                    // Ours, not another one's: still running a moment later.
                    std::thread::sleep(Duration::from_millis(200));
                    if let Ok(None) = x.child.try_wait() {
                        return Some(x);
                    }
                    break;
                }
                if let Ok(Some(_)) = x.child.try_wait() {
                    break;
                }
                std::thread::sleep(Duration::from_millis(50));
            }
            let _ = x.child.kill();
        }
        None
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("voxbrick-window-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn read_png(path: &Path) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb, "{}", path.display());
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

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
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("voxbrick starts");
    // While the window lingers after the capture, photograph the screen.
    let started = Instant::now();
    let mut screenshot = None;
    while started.elapsed() < Duration::from_secs(600) {
        if let Ok(Some(_)) = editor.try_wait() {
            break;
        }
        if capture.exists() && screenshot.is_none() {
            std::thread::sleep(Duration::from_millis(1500));
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
        std::thread::sleep(Duration::from_millis(100));
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

#[test]
fn without_a_display_the_editor_says_so_in_one_line() {
    let out = Command::new(env!("CARGO_BIN_EXE_voxbrick"))
        .args(["--window", "160x96"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env("VOXBRICK_CONFIG_DIR", scratch("nodisplay"))
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
    let recovered = app::Scene::load(&recovery, 1).unwrap();
    let mut expected = app::Scene::load(&dir.join("saved.ron"), 1).unwrap();
    let hash = |s: &app::Scene| s.world.read().content_hash();
    assert_ne!(hash(&recovered), hash(&expected));
    let command: app::editor::command::Command = ron::from_str(last).unwrap();
    command.apply(&mut expected, &dir).unwrap();
    assert_eq!(hash(&recovered), hash(&expected));
}

/// Runs xdotool with these arguments against the test's display.
fn xdotool(display: &str, args: &[&str]) -> String {
    let out = Command::new("xdotool")
        .args(args)
        .env("DISPLAY", display)
        .output()
        .expect("xdotool runs");
    assert!(
        out.status.success(),
        "xdotool {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn strokes_drawn_with_the_mouse_replay_headlessly_to_the_same_scene() {
    if !have("Xvfb") || !have("xdotool") {
        return skip("Xvfb or xdotool is not installed (packages xvfb, xdotool)");
    }
    let Some(x) = Xvfb::start_sized("800x600") else {
        return skip("Xvfb did not start");
    };
    let dir = scratch("strokes");
    let work = dir.join("work.ron");
    let made = Command::new(env!("CARGO_BIN_EXE_voxbrick"))
        .args(["new", "--terrain", "--size", "64x32x64"])
        .arg(&work)
        .output()
        .unwrap();
    assert!(made.status.success());
    let session = dir.join("session.ron");
    let mut editor = Command::new(env!("CARGO_BIN_EXE_voxbrick"))
        .arg(&work)
        .arg("--record")
        .arg(&session)
        .args(["--window", "640x400", "--validation"])
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .env("VOXBRICK_CONFIG_DIR", dir.join("config"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("voxbrick starts");
    let d = x.display.as_str();
    let window = xdotool(d, &["search", "--sync", "--name", "voxbrick"]);
    let window = window.lines().next().unwrap().to_string();
    std::thread::sleep(Duration::from_secs(4));
    xdotool(d, &["windowfocus", &window]);
    let pause = |s: f64| std::thread::sleep(Duration::from_secs_f64(s));
    // Each press waits for a frame or two with the cursor over the viewport (right of the
    // tools window), so the panels know the pointer is not theirs.
    let drag = |points: &[(i32, i32)]| {
        let (x0, y0) = points[0];
        xdotool(d, &["mousemove", &x0.to_string(), &y0.to_string()]);
        pause(1.5);
        xdotool(d, &["mousedown", "1"]);
        for (x, y) in &points[1..] {
            xdotool(d, &["mousemove", &x.to_string(), &y.to_string()]);
            pause(0.3);
        }
        xdotool(d, &["mouseup", "1"]);
        pause(1.0);
    };
    // A click that closes a menu draws nothing.
    xdotool(d, &["mousemove", "20", "11"]);
    pause(1.0);
    xdotool(d, &["click", "1"]);
    pause(1.5);
    drag(&[(480, 220)]);
    // Attach, paint, undo, redo, erase, save, quit.
    drag(&[(480, 220), (490, 230), (500, 230), (510, 230), (520, 230)]);
    xdotool(d, &["key", "p"]);
    drag(&[(450, 300), (470, 300), (490, 310)]);
    xdotool(d, &["key", "ctrl+z"]);
    pause(1.0);
    xdotool(d, &["key", "ctrl+shift+z"]);
    pause(1.0);
    xdotool(d, &["key", "x"]);
    drag(&[(560, 260), (565, 262)]);
    // Selection: a box, copy, move it, paste the copy elsewhere, fill the pasted region.
    xdotool(d, &["key", "m"]);
    drag(&[(430, 250), (450, 260), (470, 270)]);
    xdotool(d, &["key", "ctrl+c"]);
    pause(1.0);
    xdotool(d, &["key", "Right"]);
    pause(1.0);
    xdotool(d, &["key", "ctrl+v"]);
    xdotool(d, &["mousemove", "520", "200"]);
    pause(1.5);
    xdotool(d, &["click", "1"]);
    pause(1.0);
    xdotool(d, &["key", "ctrl+f"]);
    pause(1.0);
    // Quit once the save is on disk (a quit before it would ask about unsaved changes; on a
    // loaded machine the save can take longer than a fixed pause).
    let modified = || std::fs::metadata(&work).and_then(|m| m.modified()).ok();
    let before = modified();
    xdotool(d, &["key", "ctrl+s"]);
    let asked = Instant::now();
    while modified() == before && asked.elapsed() < Duration::from_secs(30) {
        pause(0.2);
    }
    pause(1.0);
    xdotool(d, &["key", "ctrl+q"]);
    // On a loaded machine a key can go missing (no window manager keeps the focus): ask again,
    // focused, every 15 s.
    let started = Instant::now();
    let mut asked_at = Instant::now();
    while started.elapsed() < Duration::from_secs(90) {
        if let Ok(Some(_)) = editor.try_wait() {
            break;
        }
        if asked_at.elapsed() > Duration::from_secs(15) {
            eprintln!(
                "the editor has not quit after {:?}: ctrl+q again",
                started.elapsed()
            );
            let _ = Command::new("xdotool")
                .args(["windowfocus", &window, "key", "ctrl+q"])
                .env("DISPLAY", d)
                .output();
            asked_at = Instant::now();
        }
        pause(0.1);
    }
    let _ = editor.kill();
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
        "the editor (validation on) failed: {stderr}"
    );
    // What the mouse and keys did, as recorded.
    let text = std::fs::read_to_string(&session).expect("the session was recorded");
    for what in [
        "mode: Attach",
        "mode: Paint",
        "Undo",
        "Redo",
        "mode: Erase",
        "Select(Replace",
        "Copy",
        "MoveSelection",
        "Paste(",
        "FillSelection",
        "Save(\"work.ron\")",
    ] {
        assert!(
            text.contains(what),
            "{what} missing from the session:\n{text}"
        );
    }
    assert_eq!(
        text.matches("Stroke(").count(),
        3,
        "attach, paint and erase; the click that closed the menu drew nothing:\n{text}"
    );
    // The same actions replayed headlessly give the scene the window saved.
    let replayed = dir.join("replayed");
    let replay = Command::new(env!("CARGO_BIN_EXE_voxbrick"))
        .arg("replay")
        .arg(&session)
        .arg("--out-dir")
        .arg(&replayed)
        .output()
        .unwrap();
    assert!(
        replay.status.success(),
        "{}",
        String::from_utf8_lossy(&replay.stderr)
    );
    let hash = |p: &Path| app::Scene::load(p, 1).unwrap().world.read().content_hash();
    let saved = hash(&work);
    assert_ne!(
        saved,
        hash(&dir.join("session-start.ron")),
        "the session changed the scene"
    );
    assert_eq!(saved, hash(&replayed.join("work.ron")));
}
