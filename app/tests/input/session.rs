//! The editor under Xvfb as the window tests drive it: started with a handshake log, moved,
//! clicked and typed at with xdotool, waited on; and the helpers the tests share.

use crate::window::{self, Report, Xvfb, have, no_vulkan, skip, xdotool};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A running editor and its handshake log.
pub struct Session {
    pub child: Child,
    pub display: String,
    pub window: String,
    pub report: Report,
    /// Where the pointer is (a move to the same place sends no event).
    pub cursor: Option<(i32, i32)>,
}

impl Session {
    /// Starts the editor with `args` on `x`, its config in `config`; None when the editor
    /// exits at once because no Vulkan device can draw a window (the test then skips).
    pub fn start(x: &Xvfb, dir: &Path, config: &Path, args: &[&str]) -> Option<Self> {
        static STARTS: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        let n = STARTS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let report_path = dir.join(format!("report-{n}.log"));
        let _ = std::fs::remove_file(&report_path);
        let mut child = Command::new(env!("CARGO_BIN_EXE_voxbrick"))
            .args(args)
            .arg("--validation")
            .env("DISPLAY", &x.display)
            .env_remove("WAYLAND_DISPLAY")
            .env("VOXBRICK_CONFIG_DIR", config)
            .env("VOXBRICK_REPORT", &report_path)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("voxbrick starts");
        let mut report = Report::new(report_path);
        // The first frame shown: the window is up and drawing.
        if report
            .wait_for(window::ANSWER_TIMEOUT, |l| l.starts_with("frame "))
            .is_none()
        {
            let _ = child.kill();
            let out = child.wait_with_output().unwrap();
            if no_vulkan(&out) {
                skip(&format!(
                    "no Vulkan device can draw a window: {}",
                    String::from_utf8_lossy(&out.stderr).trim()
                ));
                return None;
            }
            panic!(
                "the editor showed no frame: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        // Waits from here on look at every line (the file may have loaded before the frame).
        report.rewind();
        let d = x.display.as_str();
        let window = xdotool(d, &["search", "--sync", "--name", "voxbrick"]);
        let window = window.lines().next().unwrap().to_string();
        xdotool(d, &["windowfocus", &window]);
        Some(Self {
            child,
            display: x.display.clone(),
            window,
            report,
            cursor: None,
        })
    }

    /// The editor on a new 64 × 32 × 64 terrain `dir/work.ron`, recording the session to
    /// `dir/session.ron`, in a window of `size`, once the file has loaded.
    pub fn recorded(x: &Xvfb, dir: &Path, size: &str) -> Option<Self> {
        let (work, session) = (dir.join("work.ron"), dir.join("session.ron"));
        new_terrain(&work, "64x32x64");
        let mut s = Self::start(
            x,
            dir,
            &dir.join("config"),
            &[
                work.to_str().unwrap(),
                "--record",
                session.to_str().unwrap(),
                "--window",
                size,
            ],
        )?;
        s.report.wait("the file", |l| l.starts_with("loaded "));
        Some(s)
    }

    pub fn xdotool(&self, args: &[&str]) {
        xdotool(&self.display, args);
    }

    /// Moves the pointer and waits until the editor handled the move and drew a frame after
    /// it (so the panels know where the pointer is).
    pub fn mouse_to(&mut self, (x, y): (i32, i32)) {
        if self.cursor != Some((x, y)) {
            self.xdotool(&["mousemove", &x.to_string(), &y.to_string()]);
            let want = format!("input move {x} {y}");
            self.report.wait(&want, |l| l == want);
            self.cursor = Some((x, y));
        }
        self.report.frame();
    }

    /// Presses the left button, waiting for the editor to handle it.
    pub fn press(&mut self) {
        self.xdotool(&["mousedown", "1"]);
        self.report.wait("the press", |l| l == "input press Left");
    }

    /// Releases the left button, waiting for the editor to handle it.
    pub fn release(&mut self) {
        self.xdotool(&["mouseup", "1"]);
        self.report
            .wait("the release", |l| l == "input release Left");
    }

    /// A left drag through `points`, each move handled before the next; then waits for the
    /// edit line starting with `done`, if any.
    pub fn drag(&mut self, points: &[(i32, i32)], done: Option<&str>) {
        self.mouse_to(points[0]);
        self.press();
        for &p in &points[1..] {
            self.xdotool(&["mousemove", &p.0.to_string(), &p.1.to_string()]);
            let want = format!("input move {} {}", p.0, p.1);
            self.report.wait(&want, |l| l == want);
            self.cursor = Some(p);
        }
        self.release();
        if let Some(done) = done {
            self.report.wait(done, |l| l.starts_with(done));
        }
    }

    /// Sends a key chord to the window (focused first: no window manager keeps the focus),
    /// waits until the editor handled its key `code` (as the report writes it: `KeyZ`,
    /// `ArrowRight`), sending it again if it went missing (seen under Xvfb right after the
    /// window appeared), then waits for the editor's answer: the line starting with `answer`.
    pub fn key(&mut self, chord: &str, code: &str, answer: &str) {
        let handled = format!("input key Code({code}) down");
        let mut sent = 0;
        loop {
            self.xdotool(&["windowfocus", &self.window.clone(), "key", chord]);
            sent += 1;
            let mark = self.report.position();
            if self
                .report
                .wait_for(Duration::from_secs(20), |l| l == handled)
                .is_some()
            {
                self.report.set_position(mark);
                break;
            }
            assert!(sent < 4, "{chord} never reached the editor");
            eprintln!("{chord} went missing: sent again");
        }
        self.report.wait(chord, |l| l.starts_with(answer));
    }

    /// Where the widget labelled `label` shows (its centre, as the editor last said), once a
    /// frame after every line consumed so far was shown.
    pub fn widget(&mut self, label: &str) -> (i32, i32) {
        self.report.frame();
        let parse = |l: &str| -> Option<(i32, i32)> {
            let rest = l.strip_prefix("widget ")?;
            let mut parts = rest.splitn(3, ' ');
            let (x, y, name) = (parts.next()?, parts.next()?, parts.next()?);
            if name != label {
                return None;
            }
            Some((x.parse().ok()?, y.parse().ok()?))
        };
        if let Some(at) = self.report.lines().iter().rev().find_map(|l| parse(l)) {
            return at;
        }
        let line = self.report.wait(label, |l| parse(l).is_some());
        parse(&line).unwrap()
    }

    /// A left click at `p`, handled.
    pub fn click(&mut self, p: (i32, i32)) {
        self.mouse_to(p);
        self.press();
        self.release();
    }

    /// A double-click at `p`, sent again until a report line starts with `answer`: egui
    /// tells a double-click by the frames' times, and frames of a busy lavapipe machine can
    /// be slower than its 0.3 s, so a pair can read as two clicks.
    pub fn double_click(&mut self, p: (i32, i32), answer: &str) {
        self.mouse_to(p);
        for sent in 1.. {
            self.xdotool(&["click", "--repeat", "2", "--delay", "60", "1"]);
            if self
                .report
                .wait_for(Duration::from_secs(20), |l| l.contains(answer))
                .is_some()
            {
                return;
            }
            assert!(sent < 4, "a double-click never gave {answer:?}");
            eprintln!("the double-click read as clicks: sent again");
        }
    }

    /// Quits with Ctrl+Q (sent again if the key went missing) and returns the output.
    /// Quits and checks the editor ended well, without validation messages.
    pub fn quit_cleanly(self) {
        let out = self.quit();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "the editor failed: {stderr}");
        assert!(!stderr.contains("vulkan "), "validation messages: {stderr}");
    }

    pub fn quit(mut self) -> std::process::Output {
        let started = Instant::now();
        let mut asked = None::<Instant>;
        while started.elapsed() < Duration::from_secs(120) {
            if let Ok(Some(_)) = self.child.try_wait() {
                break;
            }
            if asked.is_none_or(|a| a.elapsed() > Duration::from_secs(30)) {
                let _ = Command::new("xdotool")
                    .args(["windowfocus", &self.window, "key", "ctrl+q"])
                    .env("DISPLAY", &self.display)
                    .output();
                asked = Some(Instant::now());
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        let _ = self.child.kill();
        self.child.wait_with_output().unwrap()
    }

    /// Kills the editor with SIGKILL (no chance to clean up).
    pub fn kill(mut self) {
        self.child.kill().unwrap();
        let _ = self.child.wait();
    }
}

pub fn new_terrain(path: &Path, size: &str) {
    let made = Command::new(env!("CARGO_BIN_EXE_voxbrick"))
        .args(["new", "--terrain", "--size", size])
        .arg(path)
        .output()
        .unwrap();
    assert!(made.status.success());
}

pub fn hash(p: &Path) -> u64 {
    app::formats::load(p, 1)
        .unwrap()
        .world
        .read()
        .content_hash()
}

pub fn tools_ready() -> Option<Xvfb> {
    if !have("Xvfb") || !have("xdotool") {
        skip("Xvfb or xdotool is not installed (packages xvfb, xdotool)");
        return None;
    }
    let x = Xvfb::start_sized("1024x768");
    if x.is_none() {
        skip("Xvfb did not start");
    }
    x
}
