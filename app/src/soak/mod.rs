//! The soak test: a long seeded random session fed to the editor, checked after every
//! input. Two drivers share the options, the checks' rules, the run loop and the search for
//! the shortest failing prefix:
//!
//! - [`Through::Editor`] (`editor.rs`, the default): a headless `Editor` — the window's own
//!   editor with its frames drawn offscreen — fed window input events (cursor, buttons, keys
//!   with modifiers, the wheel, resizes, dropped files) through the handlers a window's
//!   events reach: egui, the key map, picking, the tools.
//! - [`Through::Edits`] (`edits.rs`): the edit thread ([`crate::ui::jobs::EditQueue`]) fed
//!   edits directly, with frames of a bare viewport — faster, and it reaches commands the
//!   keys do not (terrain, material parameters, settings) with random arguments.
//!
//! After every input: the edit thread is alive (no panic), the validation layer has said
//! nothing, and an edit that failed left the content and the history as they were. At every
//! check (every `check_every` events and at the end): undo of the whole history gives the
//! opening content hash and redo the latest, a save and reload gives the same hash, and the
//! history's memory stays within its bound (the process's memory within the bound plus the
//! world's, with room for the allocator).
//!
//! The session is a function of the seed: a failure is re-run with fewer events to find the
//! shortest failing prefix, whose recorded session is written as a replay script.

mod editor;
mod edits;

use crate::Scene;
use crate::editor::command::{Command, TerrainSpec};
use crate::editor::script::Start;
use anyhow::{Context, Result, bail};
use glam::UVec3;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Which handlers a soak feeds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Through {
    /// Window input events into a headless editor (egui, key map, picking, tools).
    Editor,
    /// Edits into the edit thread, frames of a bare viewport.
    Edits,
}

/// What a soak runs.
#[derive(Clone, Debug)]
pub struct SoakOptions {
    /// The session's seed.
    pub seed: u64,
    /// Which handlers the session feeds.
    pub through: Through,
    /// Stop after this many events (0: only the duration stops it).
    pub events: u64,
    /// Stop after this long (None: only the event count stops it).
    pub duration: Option<Duration>,
    /// World size in voxels.
    pub size: UVec3,
    /// The viewport's largest size in pixels (resizes pick sizes up to it).
    pub view: (u32, u32),
    /// The editor's window size in pixels ([`Through::Editor`]; resizes pick sizes up to it).
    pub window: (u32, u32),
    /// Vulkan device for the viewport's frames ("gpu" or part of a name); None: no frames.
    pub device: Option<String>,
    /// Events between checks.
    pub check_every: u64,
    /// Events between frames.
    pub frame_every: u64,
    /// World worker threads.
    pub workers: usize,
    /// Where saves and the failure's script go.
    pub out_dir: PathBuf,
    /// History bound in bytes.
    pub history_budget: usize,
    /// Tests of the soak itself: event number `n` fails on purpose (the shortest failing
    /// prefix is then exactly `n` events).
    pub fail_at: Option<u64>,
}

impl Default for SoakOptions {
    fn default() -> Self {
        Self {
            seed: 1,
            through: Through::Editor,
            events: 10_000,
            duration: None,
            size: UVec3::new(64, 32, 64),
            view: (96, 64),
            window: (480, 300),
            device: Some("gpu".into()),
            check_every: 1000,
            frame_every: 8,
            workers: 2,
            out_dir: std::env::temp_dir(),
            history_budget: crate::editor::history::DEFAULT_BUDGET,
            fail_at: None,
        }
    }
}

/// What a clean soak did.
#[derive(Clone, Debug, Default)]
pub struct SoakReport {
    /// Events fed: user actions (a whole stroke, an undo / redo burst, a command, a resize, a
    /// save).
    pub events: u64,
    /// Inputs those events are made of: each stroke point, undo, redo, command, resize and
    /// frame, as the window's handlers would pass them on.
    pub inputs: u64,
    /// Wall time.
    pub elapsed: Duration,
    /// Viewport frames drawn.
    pub frames: u64,
    /// Whole-history checks passed.
    pub checks: u64,
    /// Events by kind.
    pub kinds: BTreeMap<&'static str, u64>,
    /// Edits refused (bad input by chance: each left the document as it was).
    pub refused: u64,
    /// Largest history memory seen, bytes.
    pub peak_history: usize,
    /// Largest resident memory seen, bytes (0 where /proc is missing).
    pub peak_rss: u64,
}

/// A failed soak: where, why, and the shortest failing prefix as a replay script.
#[derive(Debug)]
pub struct SoakFailure {
    /// The seed.
    pub seed: u64,
    /// The event (1-based) at which the first run failed.
    pub event: u64,
    /// The shortest failing prefix, in events.
    pub shortest: u64,
    /// What went wrong.
    pub message: String,
    /// The recorded session of the shortest failing run (replay with `voxbrick replay`).
    pub script: Option<PathBuf>,
}

impl std::fmt::Display for SoakFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "soak seed {} failed at event {} (shortest failing prefix: {} events): {}",
            self.seed, self.event, self.shortest, self.message
        )?;
        if let Some(s) = &self.script {
            write!(f, "; its session: {} (voxbrick replay)", s.display())?;
        }
        Ok(())
    }
}

/// SplitMix64: small, fast, and the same sequence everywhere.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n.max(1)
    }
    fn range(&mut self, lo: i64, hi: i64) -> i64 {
        lo + self.below((hi - lo + 1) as u64) as i64
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn chance(&mut self, p: f64) -> bool {
        self.unit() < p
    }
    fn pick<T: Copy>(&mut self, items: &[T]) -> T {
        items[self.below(items.len() as u64) as usize]
    }
}

/// The process's resident memory in bytes (0 where /proc is missing).
fn rss() -> u64 {
    std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| s.split_whitespace().nth(1)?.parse::<u64>().ok())
        .map_or(0, |pages| pages * 4096)
}

/// A soak's start: a world of the options' size with a terrain of the seed.
fn start_scene(opts: &SoakOptions) -> Result<(Scene, Start)> {
    let terrain = TerrainSpec {
        seed: opts.seed as u32,
        scale: 40.0,
        octaves: 4,
        height_range: (2, opts.size.y * 2 / 3),
        water_level: opts.size.y / 4,
        noise: Default::default(),
        bands: Default::default(),
    };
    let dims = brickmap::GridDims::from_voxels(opts.size).context("soak world size")?;
    let mut scene = Scene::empty(dims, opts.workers)?;
    Command::GenerateTerrain(terrain.clone())
        .apply(&mut scene, &opts.out_dir)
        .context("soak terrain")?;
    let start = Start::New {
        size: (opts.size.x, opts.size.y, opts.size.z),
        terrain: Some(terrain),
    };
    Ok((scene, start))
}

/// A soak session's driver: what feeds the editor and checks it.
trait Driver: Sized {
    /// The session at its start (the seed's scene open, nothing done).
    fn start(opts: &SoakOptions) -> Result<Self>;
    /// Event number `n` (1-based) and its per-input checks.
    fn event(&mut self, n: u64) -> Result<()>;
    /// The whole-history check.
    fn check(&mut self) -> Result<()>;
    /// The report so far.
    fn report(&mut self) -> &mut SoakReport;
    /// The recorded session as a replay script.
    fn script(&self) -> String;
    /// The session's end (GPU work waited for, the editor closed).
    fn finish(&mut self) -> Result<()>;
}

/// The message of a panic caught by the run loop.
fn panic_message(panic: Box<dyn std::any::Any + Send>) -> String {
    let what = panic
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_default();
    format!("panic: {what}")
}

/// Runs `d` until the options say stop or something fails (the event number and why).
fn run<D: Driver>(
    d: &mut D,
    opts: &SoakOptions,
    limit: u64,
) -> std::result::Result<(), (u64, String)> {
    let started = Instant::now();
    let mut n = 0;
    loop {
        let over_time = opts.duration.is_some_and(|t| started.elapsed() >= t);
        if (limit > 0 && n >= limit) || over_time {
            break;
        }
        n += 1;
        d.report().events = n;
        let step = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            d.event(n)?;
            if opts.fail_at == Some(n) {
                bail!("failing on purpose at event {n} (a test of the soak)");
            }
            if n.is_multiple_of(opts.check_every.max(1)) {
                d.check()?;
            }
            Ok::<(), anyhow::Error>(())
        }));
        match step {
            Ok(Ok(())) => {}
            Ok(Err(e)) => return Err((n, format!("{e:#}"))),
            Err(panic) => return Err((n, panic_message(panic))),
        }
    }
    let last = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        d.check()?;
        d.finish()
    }));
    match last {
        Ok(Ok(())) => {}
        Ok(Err(e)) => return Err((n, format!("final check: {e:#}"))),
        Err(panic) => return Err((n, format!("final check: {}", panic_message(panic)))),
    }
    d.report().elapsed = started.elapsed();
    Ok(())
}

/// Runs a soak. On failure the same seed is re-run with fewer events (a binary search) for
/// the shortest failing prefix, whose session is written to `out_dir` as a replay script.
pub fn soak(opts: &SoakOptions) -> std::result::Result<SoakReport, SoakFailure> {
    match opts.through {
        Through::Editor => soak_with::<editor::EditorSession>(opts),
        Through::Edits => soak_with::<edits::Session>(opts),
    }
}

fn soak_with<D: Driver>(opts: &SoakOptions) -> std::result::Result<SoakReport, SoakFailure> {
    let fail = |event, shortest, message: String, script| SoakFailure {
        seed: opts.seed,
        event,
        shortest,
        message,
        script,
    };
    let mut session = D::start(opts).map_err(|e| fail(0, 0, format!("{e:#}"), None))?;
    let limit = opts.events;
    let (event, message) = match run(&mut session, opts, limit) {
        Ok(()) => return Ok(session.report().clone()),
        Err(f) => f,
    };
    drop(session);
    // The shortest prefix that still fails (a session is a function of its seed).
    let (mut lo, mut hi) = (0u64, event);
    let mut failing: Option<String> = None;
    while lo + 1 < hi {
        let mid = lo + (hi - lo) / 2;
        let probe = SoakOptions {
            events: mid,
            duration: None,
            ..opts.clone()
        };
        let Ok(mut s) = D::start(&probe) else {
            break;
        };
        match run(&mut s, &probe, mid) {
            Err(_) => {
                hi = mid;
                failing = Some(s.script());
            }
            Ok(()) => lo = mid,
        }
    }
    let script = match failing {
        Some(text) => Some(text),
        None => {
            let probe = SoakOptions {
                events: hi,
                duration: None,
                ..opts.clone()
            };
            D::start(&probe).ok().map(|mut s| {
                let _ = run(&mut s, &probe, hi);
                s.script()
            })
        }
    };
    let path = script.and_then(|text| {
        let p = opts
            .out_dir
            .join(format!("soak-failure-seed-{}.ron", opts.seed));
        crate::atomic::write_atomic(&p, |w: &mut dyn std::io::Write| {
            w.write_all(text.as_bytes())
        })
        .ok()
        .map(|()| p)
    });
    Err(fail(event, hi, message, path))
}
