//! What the window tests share: their own Xvfb server, skipping (or failing under
//! VOXBRICK_REQUIRE_GPU=1) where no display or Vulkan driver exists, xdotool, and the editor's
//! handshake log (`VOXBRICK_REPORT`): a test waits for the line that answers its input
//! instead of sleeping.
#![allow(dead_code)] // each test file uses part of it

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

pub fn require() -> bool {
    std::env::var("VOXBRICK_REQUIRE_GPU").as_deref() == Ok("1")
}

pub fn skip(why: &str) {
    assert!(!require(), "{why}, and VOXBRICK_REQUIRE_GPU=1");
    eprintln!("SKIPPED: {why}; VOXBRICK_REQUIRE_GPU=1 makes this a failure");
}

/// The editor exited because this machine has no Vulkan device that can draw a window.
pub fn no_vulkan(out: &std::process::Output) -> bool {
    let stderr = String::from_utf8_lossy(&out.stderr);
    !out.status.success()
        && (stderr.contains("no usable Vulkan") || stderr.contains("no Vulkan device"))
}

pub fn have(tool: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {tool}")])
        .stdout(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// An Xvfb server of our own, killed on drop.
pub struct Xvfb {
    child: Child,
    /// The display, as DISPLAY wants it.
    pub display: String,
}

impl Xvfb {
    pub fn start() -> Option<Self> {
        Self::start_sized("320x240")
    }

    pub fn start_sized(size: &str) -> Option<Self> {
        // Tests of this file run in parallel: each takes its own number, and a server that
        // lost the race for a number (it exits at once) makes it try the next.
        static NEXT: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        let mut tries = 0;
        for _ in 0..400 {
            if tries == 20 {
                break;
            }
            let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            let number = 90 + (std::process::id() * 7 + n) % 400;
            if !free_display(number) {
                continue;
            }
            tries += 1;
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
    /// Asks the server to end (it removes its lock file and socket then), and kills it if
    /// it has not ended a second later.
    fn drop(&mut self) {
        let _ = Command::new("kill")
            .arg(self.child.id().to_string())
            .stderr(Stdio::null())
            .status();
        let started = Instant::now();
        while started.elapsed() < Duration::from_secs(1) {
            if let Ok(Some(_)) = self.child.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Whether display `number` is free: no lock file, or only the lock and socket of a server
/// that is gone (a killed one leaves both), which are removed.
fn free_display(number: u32) -> bool {
    let lock = format!("/tmp/.X{number}-lock");
    let socket = format!("/tmp/.X11-unix/X{number}");
    match std::fs::read_to_string(&lock) {
        Ok(text) => {
            let alive = text
                .trim()
                .parse::<u32>()
                .is_ok_and(|pid| Path::new(&format!("/proc/{pid}")).exists());
            if alive {
                return false;
            }
            let _ = std::fs::remove_file(&lock);
            let _ = std::fs::remove_file(&socket);
            !Path::new(&lock).exists() && !Path::new(&socket).exists()
        }
        // No lock: free unless a socket is left without one.
        Err(_) => !Path::new(&socket).exists(),
    }
}

/// A scratch folder for this test, removed when it passes.
pub fn scratch(name: &str) -> app::scratch::Scratch {
    app::scratch::Scratch::new(&format!("window-{name}"))
}

pub fn read_png(path: &Path) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb, "{}", path.display());
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

/// Runs xdotool with these arguments against the test's display.
pub fn xdotool(display: &str, args: &[&str]) -> String {
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

/// Replays a script headlessly with the `voxbrick` binary at `bin`, its files into `out`;
/// fails the test with the replay's errors.
pub fn replay(bin: &str, script: &Path, out: &Path) {
    let run = Command::new(bin)
        .arg("replay")
        .arg(script)
        .arg("--out-dir")
        .arg(out)
        .output()
        .expect("voxbrick runs");
    assert!(
        run.status.success(),
        "replaying {}: {}",
        script.display(),
        String::from_utf8_lossy(&run.stderr)
    );
}

/// The editor's handshake log, read as it grows.
pub struct Report {
    path: PathBuf,
    /// Lines already consumed by waits.
    seen: usize,
}

/// How long a wait for one answer may take before the test fails (a frame on a loaded
/// machine under lavapipe takes seconds; an answer never takes minutes).
pub const ANSWER_TIMEOUT: Duration = Duration::from_secs(180);

impl Report {
    /// The log at `path` (the editor creates it).
    pub fn new(path: PathBuf) -> Self {
        Self { path, seen: 0 }
    }

    /// Every line so far.
    pub fn lines(&self) -> Vec<String> {
        std::fs::read_to_string(&self.path)
            .unwrap_or_default()
            .lines()
            .map(str::to_string)
            .collect()
    }

    /// Forgets what was consumed: the next wait looks at every line from the first.
    pub fn rewind(&mut self) {
        self.seen = 0;
    }

    /// How many lines are consumed.
    pub fn position(&self) -> usize {
        self.seen
    }

    /// Consumes exactly the first `seen` lines.
    pub fn set_position(&mut self, seen: usize) {
        self.seen = seen;
    }

    /// Marks every line so far as consumed.
    pub fn skip_past(&mut self) {
        self.seen = self.lines().len();
    }

    /// Waits for the first line not yet consumed that satisfies `pred`, consumes it and the
    /// lines before it and returns it; None after `timeout`.
    pub fn wait_for(&mut self, timeout: Duration, pred: impl Fn(&str) -> bool) -> Option<String> {
        let started = Instant::now();
        loop {
            let lines = self.lines();
            if let Some(k) = lines.iter().skip(self.seen).position(|l| pred(l)) {
                self.seen += k + 1;
                return Some(lines[self.seen - 1].clone());
            }
            if started.elapsed() > timeout {
                return None;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// [`Report::wait_for`] that fails the test, showing the log's tail, when no line comes.
    pub fn wait(&mut self, what: &str, pred: impl Fn(&str) -> bool) -> String {
        match self.wait_for(ANSWER_TIMEOUT, pred) {
            Some(line) => line,
            None => {
                let lines = self.lines();
                let tail = lines[lines.len().saturating_sub(30)..].join("\n");
                panic!("no answer to {what} within {ANSWER_TIMEOUT:?}; the report ends:\n{tail}")
            }
        }
    }

    /// Waits until a frame is shown after every line consumed so far whose traced image
    /// shows them too (not "pending": the trace runs at its own pace, and the frames in
    /// between show the UI over the previous image).
    pub fn frame(&mut self) {
        self.wait("a frame", |l| {
            l.starts_with("frame ") && !l.ends_with(" pending")
        });
    }
}
