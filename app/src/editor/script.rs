//! Replay scripts: a RON header (format version, how the document starts, worker count) and
//! a list of steps (any command, undo, redo, save, export, open, render, and assertions).
//! Replay reports each step and stops at the first failure with the step number and what
//! differed. Paths to read (imports, start files) are relative to the script's folder; paths
//! to write go to the output folder (the script's folder unless told otherwise).
//!
//! ```text
//! (
//!     format_version: 1,
//!     start: New(size: (128, 64, 128)),
//!     workers: Some(2),
//!     steps: [
//!         Do(Stroke((mode: Attach, shape: Sphere, size: 6.0, material: 0, points: [(40.0, 20.0, 40.0)]))),
//!         Mark("one sphere"),
//!         Undo,
//!         ExpectSolidCount(0),
//!         Redo,
//!         ExpectHashOf("one sphere"),
//!         ExpectVoxel(at: (40, 20, 40), material: Some(0)),
//!         Save("sphere.ron"),
//!         Render((spp: 4, width: 32, height: 18, out: Some("sphere.png"), mean_min: Some((0.01, 0.01, 0.01)))),
//!     ],
//! )
//! ```

use super::Document;
use super::command::{Command, TerrainSpec};
use super::history::History;
use crate::scene::Scene;
use anyhow::{Context, Result, ensure};
use brickmap::GridDims;
use glam::{IVec3, UVec3};
use render::Camera;
use render::viewport::RenderHow;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The script format version this program writes and reads.
pub const SCRIPT_VERSION: u32 = 1;

/// A replay script.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Script {
    /// Format version (1).
    pub format_version: u32,
    /// How the document starts.
    pub start: Start,
    /// Worker threads (None: one per core); `voxbrick replay --workers` overrides it.
    #[serde(default)]
    pub workers: Option<usize>,
    /// The steps.
    pub steps: Vec<Step>,
}

/// The starting document.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Start {
    /// A new empty scene of a size in voxels, optionally with generated terrain.
    New {
        /// Width, height, depth in voxels (rounded up to whole bricks).
        size: (u32, u32, u32),
        /// Terrain to generate first (not an undo step).
        #[serde(default)]
        terrain: Option<TerrainSpec>,
    },
    /// A .ron or .vox file, relative to the script.
    File(String),
    /// The built-in default scene (what the editor opens without a file).
    Default,
}

/// Bounds on a rendered image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RenderStep {
    /// Camera (None: the scene's).
    #[serde(default)]
    pub camera: Option<Camera>,
    /// Samples per pixel.
    pub spp: u32,
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Bounces (None: the scene's).
    #[serde(default)]
    pub bounces: Option<u32>,
    /// Seed.
    #[serde(default)]
    pub seed: u64,
    /// PNG to write (output folder).
    #[serde(default)]
    pub out: Option<String>,
    /// Lower bound of the image's mean linear RGB.
    #[serde(default)]
    pub mean_min: Option<(f32, f32, f32)>,
    /// Upper bound of the image's mean linear RGB.
    #[serde(default)]
    pub mean_max: Option<(f32, f32, f32)>,
    /// On the GPU, also render twice on the CPU reference and require the GPU image to differ
    /// from it by no more than sampling noise: RMS(GPU − CPU₁) < 1.3·RMS(CPU₂ − CPU₁) (each
    /// leaving out the largest 1% of squared differences), and channel means within 2% plus
    /// four standard errors.
    #[serde(default)]
    pub compare_cpu: bool,
}

/// One script step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Step {
    /// Execute a command.
    Do(Command),
    /// Undo the latest step.
    Undo,
    /// Redo the latest undone step.
    Redo,
    /// Save (project or .vox by extension) to the output folder.
    Save(String),
    /// Export .vox to the output folder.
    Export(String),
    /// Replace the document by a file (from the output folder if it exists there, else the
    /// script's folder); the history starts empty.
    Open(String),
    /// Render on the CPU reference renderer, optionally checking the mean.
    Render(RenderStep),
    /// Remember the current content hash under a name.
    Mark(String),
    /// The content hash equals a mark's.
    ExpectHashOf(String),
    /// The content hash equals this value (hex, as `voxbrick info` prints it).
    ExpectHash(String),
    /// A voxel is solid with a material (`material: Some(m)`) or empty (`None`).
    ExpectVoxel {
        /// The voxel.
        at: IVec3,
        /// Its expected material, or None for empty.
        material: Option<u8>,
    },
    /// The number of solid voxels.
    ExpectSolidCount(u64),
    /// A node of the object tree: exists, and (each where given) has this name, world
    /// placement, visibility, and (an object) this many solid voxels in its model.
    ExpectObject {
        /// The node.
        node: brickmap::objects::NodeId,
        /// Its name.
        #[serde(default)]
        name: Option<String>,
        /// Its placement in the world (its parents' composed in).
        #[serde(default)]
        placement: Option<brickmap::objects::Placement>,
        /// Shown.
        #[serde(default)]
        visible: Option<bool>,
        /// Solid voxels of its model.
        #[serde(default)]
        voxels: Option<u64>,
        /// Its parent group.
        #[serde(default)]
        parent: Option<brickmap::objects::NodeId>,
        /// Its layer (an object's).
        #[serde(default)]
        layer: Option<brickmap::objects::LayerId>,
    },
    /// Steps that can be undone and redone.
    ExpectHistory {
        /// Undoable steps.
        undo: usize,
        /// Redoable steps.
        redo: usize,
    },
}

impl Step {
    fn name(&self) -> String {
        match self {
            Step::Do(c) => c.label(),
            other => format!("{other:?}")
                .split(['(', ' '])
                .next()
                .unwrap_or("step")
                .to_string(),
        }
    }
}

/// How to replay.
#[derive(Clone, Debug, Default)]
pub struct ReplayOptions {
    /// Overrides the script's worker count.
    pub workers: Option<usize>,
    /// Where written files go (default: the script's folder).
    pub out_dir: Option<PathBuf>,
    /// Render device for render steps: "cpu" (the reference), "gpu" (the best Vulkan device)
    /// or part of a Vulkan device's name.
    pub device: String,
    /// History budget in bytes (default 512 MiB).
    pub history_budget: Option<usize>,
}

/// What a replay ends with.
pub struct Replayed {
    /// The document after the last step.
    pub document: Document,
    /// Steps run.
    pub steps: usize,
}

/// Parses a script.
pub fn parse(text: &str) -> Result<Script> {
    #[derive(Deserialize)]
    struct Probe {
        format_version: u32,
    }
    let probe: Probe = ron::from_str(text).context("not a voxbrick script")?;
    ensure!(
        probe.format_version == SCRIPT_VERSION,
        "script format version {} is not {SCRIPT_VERSION}",
        probe.format_version
    );
    Ok(ron::from_str(text)?)
}

/// Replays a script file; `report` receives one line per step.
pub fn replay_file(
    path: &Path,
    options: &ReplayOptions,
    report: &mut dyn FnMut(&str),
) -> Result<Replayed> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let script = parse(&text).with_context(|| path.display().to_string())?;
    let folder = path
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."));
    replay(&script, &folder, options, report)
}

/// Replays a parsed script whose relative paths start at `folder`.
pub fn replay(
    script: &Script,
    folder: &Path,
    options: &ReplayOptions,
    report: &mut dyn FnMut(&str),
) -> Result<Replayed> {
    let (mut run, mut document) = ScriptRun::start(script, folder, options)?;
    while let Some(line) = run.step(script, &mut document)? {
        report(&line);
    }
    Ok(Replayed {
        document,
        steps: script.steps.len(),
    })
}

/// A replay in progress, one step at a time (the live editor runs one step per frame, so
/// the viewport shows each edit).
pub struct ScriptRun {
    out_dir: PathBuf,
    options: ReplayOptions,
    marks: HashMap<String, u64>,
    next: usize,
}

impl ScriptRun {
    /// The run and the script's starting document; relative paths start at `folder`.
    pub fn start(
        script: &Script,
        folder: &Path,
        options: &ReplayOptions,
    ) -> Result<(Self, Document)> {
        let workers = options.workers.or(script.workers).unwrap_or(0);
        let out_dir = options
            .out_dir
            .clone()
            .unwrap_or_else(|| folder.to_path_buf());
        std::fs::create_dir_all(&out_dir)
            .with_context(|| format!("creating the output folder {}", out_dir.display()))?;
        let history = || {
            History::with_budget(
                options
                    .history_budget
                    .unwrap_or(super::history::DEFAULT_BUDGET),
            )
        };
        let scene = match &script.start {
            Start::New { size, terrain } => {
                let dims = GridDims::from_voxels(UVec3::new(size.0, size.1, size.2))
                    .context("start: grid size")?;
                let mut doc = Document::new(Scene::empty(dims, workers)?, history());
                if let Some(t) = terrain {
                    Command::GenerateTerrain(t.clone())
                        .apply(&mut doc.scene, folder)
                        .context("start: terrain")?;
                }
                doc.scene
            }
            Start::File(f) => crate::formats::load(&folder.join(f), workers).context("start")?,
            Start::Default => {
                crate::builtin::default_scene(crate::builtin::SceneSize::Full, workers)
                    .context("start: the default scene")?
            }
        };
        let mut document = Document::new(scene, history());
        document.folder = folder.to_path_buf();
        let run = Self {
            out_dir,
            options: options.clone(),
            marks: HashMap::new(),
            next: 0,
        };
        Ok((run, document))
    }

    /// Runs the next step: its report line, or None when every step ran. An error names
    /// the step.
    pub fn step(&mut self, script: &Script, document: &mut Document) -> Result<Option<String>> {
        let Some(step) = script.steps.get(self.next) else {
            return Ok(None);
        };
        self.next += 1;
        let n = self.next;
        let line = run_step(
            document,
            step,
            &self.out_dir,
            &self.options,
            &mut self.marks,
        )
        .with_context(|| format!("step {n} ({})", step.name()))?;
        Ok(Some(format!("step {n:>4}  {line}")))
    }

    /// Steps run so far.
    pub fn steps_run(&self) -> usize {
        self.next
    }
}

fn hash(doc: &Document) -> u64 {
    doc.scene.world.read().content_hash()
}

fn run_step(
    doc: &mut Document,
    step: &Step,
    out_dir: &Path,
    options: &ReplayOptions,
    marks: &mut HashMap<String, u64>,
) -> Result<String> {
    Ok(match step {
        Step::Do(command) => {
            let dropped = doc.execute(command.clone())?.dropped;
            let note = if dropped > 0 {
                format!(" ({dropped} old history steps dropped to fit the budget)")
            } else {
                String::new()
            };
            format!("{}{note}", command.label())
        }
        Step::Undo => format!("undo {}", doc.undo()?),
        Step::Redo => format!("redo {}", doc.redo()?),
        Step::Save(p) | Step::Export(p) => {
            let path = out_dir.join(p);
            if matches!(step, Step::Export(_)) {
                ensure!(
                    crate::formats::Format::of(&path)? != crate::formats::Format::Project,
                    "export writes .vox, .qb or .schem files"
                );
            }
            doc.save(&path)?;
            format!("wrote {}", path.display())
        }
        Step::Open(p) => {
            let in_out = out_dir.join(p);
            let path = if in_out.exists() {
                in_out
            } else {
                doc.folder.join(p)
            };
            let scene = crate::formats::load(&path, doc.scene.world.workers())?;
            let budget = options
                .history_budget
                .unwrap_or(super::history::DEFAULT_BUDGET);
            let folder = std::mem::take(&mut doc.folder);
            *doc = Document::new(scene, History::with_budget(budget));
            doc.folder = folder;
            doc.path = Some(path.clone());
            format!("opened {}", path.display())
        }
        Step::Render(r) => render_step(doc, r, out_dir, options)?,
        Step::Mark(name) => {
            marks.insert(name.clone(), hash(doc));
            format!("mark {name:?} = {:016x}", hash(doc))
        }
        Step::ExpectHashOf(name) => {
            let want = *marks
                .get(name)
                .with_context(|| format!("no mark {name:?}"))?;
            ensure!(
                hash(doc) == want,
                "content hash {:016x}, mark {name:?} has {want:016x}",
                hash(doc)
            );
            format!("hash equals mark {name:?}")
        }
        Step::ExpectHash(hex) => {
            let want = u64::from_str_radix(hex.trim_start_matches("0x"), 16)
                .with_context(|| format!("{hex:?} is not a hex hash"))?;
            ensure!(
                hash(doc) == want,
                "content hash {:016x}, expected {want:016x}",
                hash(doc)
            );
            format!("hash {want:016x}")
        }
        Step::ExpectVoxel { at, material } => {
            let got = doc.scene.world.read().voxel(*at)?;
            ensure!(
                got == *material,
                "voxel {at} is {got:?}, expected {material:?}"
            );
            format!("voxel {at} is {material:?}")
        }
        Step::ExpectSolidCount(want) => {
            let got = doc.scene.world.read().solid_count();
            ensure!(got == *want, "{got} solid voxels, expected {want}");
            format!("{want} solid voxels")
        }
        Step::ExpectObject {
            node,
            name,
            placement,
            visible,
            voxels,
            parent,
            layer,
        } => {
            let objects = doc.scene.objects();
            let tree = objects.tree();
            let n = tree
                .node(*node)
                .with_context(|| format!("object #{}", node.0))?;
            let at = tree.world_placement(*node)?;
            let (count, on) = match n.kind {
                brickmap::objects::NodeKind::Object { model, layer } => {
                    (objects.model(model).map(|m| m.solid_count()), Some(layer))
                }
                brickmap::objects::NodeKind::Group { .. } => (None, None),
            };
            let checks = [
                (
                    name.as_ref().is_none_or(|w| *w == n.name),
                    format!("named {:?}", n.name),
                ),
                (placement.is_none_or(|w| w == at), format!("placed {at:?}")),
                (
                    visible.is_none_or(|w| w == n.visible),
                    format!("visible {}", n.visible),
                ),
                (
                    voxels.is_none_or(|w| Some(w) == count),
                    format!("{count:?} voxels"),
                ),
                (
                    parent.is_none_or(|w| Some(w) == n.parent()),
                    format!("under {:?}", n.parent()),
                ),
                (
                    layer.is_none_or(|w| Some(w) == on),
                    format!("on layer {on:?}"),
                ),
            ];
            for (ok, got) in &checks {
                ensure!(*ok, "object #{} is {got}, not as expected", node.0);
            }
            format!("object #{} as expected", node.0)
        }
        Step::ExpectHistory { undo, redo } => {
            let got = (doc.history.undo_len(), doc.history.redo_len());
            ensure!(
                got == (*undo, *redo),
                "history has {} undo and {} redo steps, expected {undo} and {redo}",
                got.0,
                got.1
            );
            format!("history {undo} undo, {redo} redo")
        }
    })
}

fn render_step(
    doc: &Document,
    r: &RenderStep,
    out_dir: &Path,
    options: &ReplayOptions,
) -> Result<String> {
    ensure!(
        r.spp > 0 && r.width > 0 && r.height > 0 && r.width <= 4096 && r.height <= 4096,
        "render size and samples must be positive (at most 4096 pixels a side)"
    );
    let mut params = doc.scene.params.clone();
    if let Some(c) = &r.camera {
        c.validate()?;
        params.camera = c.clone();
    }
    if let Some(b) = r.bounces {
        ensure!((1..=64).contains(&b), "bounces {b} is outside 1..=64");
        params.settings.max_bounces = b;
    }
    let view = doc.scene.world.read();
    let job = |seed| render::cpu::RenderJob {
        width: r.width,
        height: r.height,
        spp: r.spp,
        seed,
    };
    let cpu = |seed| render::cpu::CpuScene::new(&view, &params).render(&job(seed));
    let (image, device) = if options.device == "cpu" {
        ensure!(
            !r.compare_cpu,
            "compare_cpu needs a GPU device (replay with --device gpu)"
        );
        (cpu(r.seed), "cpu".to_string())
    } else {
        let mut session = crate::gpu::session(&options.device, &view)
            .context("no GPU for render steps (replay with --device cpu for the CPU reference)")?;
        let rendered = session.render(&view, &params, &job(r.seed), RenderHow::SCENE)?;
        (rendered.image, session.ctx().name.clone())
    };
    ensure!(image.all_finite(), "the image has NaN or infinite pixels");
    let mean = image.mean();
    if let Some((a, b, c)) = r.mean_min {
        ensure!(
            mean[0] >= a as f64 && mean[1] >= b as f64 && mean[2] >= c as f64,
            "image mean {mean:?} is below {:?}",
            (a, b, c)
        );
    }
    if let Some((a, b, c)) = r.mean_max {
        ensure!(
            mean[0] <= a as f64 && mean[1] <= b as f64 && mean[2] <= c as f64,
            "image mean {mean:?} is above {:?}",
            (a, b, c)
        );
    }
    let mut note = String::new();
    if r.compare_cpu {
        let (c1, c2) = (cpu(r.seed.wrapping_add(1)), cpu(r.seed.wrapping_add(2)));
        let (gc, cc) = (rms(&image, &c1), rms(&c2, &c1));
        ensure!(
            gc < 1.3 * cc + 1e-6,
            "GPU image differs from the CPU reference more than sampling noise: RMS {gc:.5} vs {cc:.5}; means GPU {:?}, CPU {:?}, CPU again {:?}",
            mean,
            c1.mean(),
            c2.mean()
        );
        for (k, (g, c)) in mean.iter().zip(c1.mean()).enumerate() {
            let g = *g;
            let tolerance =
                0.02 * c.abs().max(1e-3) + 4.0 * cc / (image.pixels.len() as f64).sqrt();
            ensure!(
                (g - c).abs() <= tolerance,
                "channel {k}: GPU mean {g:.5}, CPU mean {c:.5}"
            );
        }
        note = format!(", matches the CPU reference (RMS {gc:.4} vs noise {cc:.4})");
    }
    if let Some(out) = &r.out {
        let path = out_dir.join(out);
        crate::atomic::write_atomic(&path, |w| image.write_png(w, params.settings.exposure))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(format!(
        "rendered {}x{} at {} spp on {device}, mean ({:.4}, {:.4}, {:.4}){note}",
        r.width, r.height, r.spp, mean[0], mean[1], mean[2]
    ))
}

/// Root-mean-square difference of two images over every channel, leaving out the largest 1%
/// of squared differences: caustics make pixel values heavy-tailed, and a few pixels would
/// otherwise decide the comparison. Applied alike to GPU−CPU and CPU−CPU.
fn rms(a: &render::Image, b: &render::Image) -> f64 {
    let mut sq: Vec<f64> = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(x, y)| (0..3).map(move |k| (x[k] as f64 - y[k] as f64).powi(2)))
        .collect();
    sq.sort_by(f64::total_cmp);
    let keep = sq.len() - sq.len() / 100;
    (sq[..keep].iter().sum::<f64>() / keep.max(1) as f64).sqrt()
}

/// Records what an editor session does, as a script.
#[derive(Clone, Debug, Default)]
pub struct Recorder {
    steps: Vec<Step>,
}

impl Recorder {
    /// Records a step (call after it succeeded).
    pub fn record(&mut self, step: Step) {
        self.steps.push(step);
    }
    /// The script of everything recorded, starting from `start`.
    pub fn script(&self, start: Start, workers: Option<usize>) -> Script {
        Script {
            format_version: SCRIPT_VERSION,
            start,
            workers,
            steps: self.steps.clone(),
        }
    }
    /// The script as RON text, one step per line.
    pub fn to_ron(&self, start: Start, workers: Option<usize>) -> String {
        let script = self.script(start, workers);
        let compact = ron::ser::PrettyConfig::new()
            .compact_structs(true)
            .compact_arrays(true);
        let one = |v: &dyn erased::Ron| v.ron(&compact);
        let steps: Vec<String> = script
            .steps
            .iter()
            .map(|s| format!("        {},", one(s)))
            .collect();
        format!(
            "(\n    format_version: {},\n    start: {},\n    workers: {},\n    steps: [\n{}\n    ],\n)\n",
            script.format_version,
            one(&script.start),
            one(&script.workers),
            steps.join("\n")
        )
    }
}

mod erased {
    /// Serializes any value to compact RON (a tiny object-safe wrapper).
    pub trait Ron {
        fn ron(&self, config: &ron::ser::PrettyConfig) -> String;
    }
    impl<T: serde::Serialize> Ron for T {
        fn ron(&self, config: &ron::ser::PrettyConfig) -> String {
            ron::ser::to_string_pretty(self, config.clone()).expect("script values serialize")
        }
    }
}
