//! The soak through the edit thread: seeded random edits submitted to an [`EditQueue`] — the
//! queue and document operations the window's handlers submit to — strokes of every mode and
//! shape begun, extended point by point, ended or cancelled; selections and their operations,
//! copy / cut / paste, palette and material edits with random parameters, flood fills,
//! terrain generation, bursts of undo and redo, camera, sun, sky and settings, saves and
//! re-opens — with a bare viewport's frames (validation on) at sizes that change as a resized
//! window's would. Each edit is waited for, so each event's invariants are checked on its own.

use super::{Rng, SoakOptions, SoakReport, rss};
use crate::editor::Document;
use crate::editor::command::{
    Axis, BrushMode, BrushShape, Command, KindSpec, MaterialSpec, Mirror, PaintMode, Stroke,
    TerrainSpec,
};
use crate::editor::history::History;
use crate::editor::script::{Recorder, Start, Step};
use crate::selection::SelectOp;
use crate::ui::jobs::{Edit, EditQueue, Edited};
use anyhow::{Context, Result, anyhow, bail, ensure};
use glam::{DVec3, IVec3};
use render::viewport::{FrameRequest, Viewport};
use std::sync::{Arc, RwLock};
use std::time::Duration;

type Shared = Arc<RwLock<Document>>;

/// One soak session.
pub(super) struct Session {
    opts: SoakOptions,
    rng: Rng,
    doc: Shared,
    edits: EditQueue,
    viewport: Option<Viewport>,
    view_size: (u32, u32),
    /// The content hash the history goes back to (the last open).
    opening: u64,
    report: SoakReport,
    baseline_rss: u64,
    start: Start,
}

fn hash(doc: &Shared) -> u64 {
    doc.read()
        .unwrap_or_else(|p| p.into_inner())
        .scene
        .world
        .read()
        .content_hash()
}

impl Session {
    fn new(opts: &SoakOptions) -> Result<Self> {
        let (scene, start) = super::start_scene(opts)?;
        let mut doc = Document::new(scene, History::with_budget(opts.history_budget));
        doc.folder = opts.out_dir.clone();
        doc.recorder = Some(Recorder::default());
        let viewport = match &opts.device {
            Some(device) => {
                let ctx = crate::gpu::context(device, true)?;
                Some(Viewport::new(ctx, &doc.scene.world.read())?)
            }
            None => None,
        };
        let opening = doc.scene.world.read().content_hash();
        Ok(Self {
            rng: Rng(opts.seed ^ 0x5EED_50A4),
            doc: Arc::new(RwLock::new(doc)),
            edits: EditQueue::new(Arc::new(|| {})),
            viewport,
            view_size: opts.view,
            opening,
            report: SoakReport::default(),
            baseline_rss: rss(),
            start,
            opts: opts.clone(),
        })
    }

    /// Submits an edit and waits for its result (the window's loop polls; the soak waits, so
    /// each event's invariants are checked on its own).
    fn edit(&mut self, edit: Edit) -> Result<Edited> {
        self.report.inputs += 1;
        self.edits.submit(&self.doc, edit);
        let edited = self
            .edits
            .done
            .recv_timeout(Duration::from_secs(600))
            .map_err(|_| anyhow!("the edit thread died or hung (a panic?)"))?;
        self.edits.finished();
        Ok(edited)
    }

    /// The history's lengths and the content hash: what a refused edit must leave alone.
    fn state(&self) -> (u64, usize, usize) {
        let d = self.doc.read().unwrap_or_else(|p| p.into_inner());
        (
            d.scene.world.read().content_hash(),
            d.history.undo_len(),
            d.history.redo_len(),
        )
    }

    /// A command: fine whether it succeeds or is refused, but a refusal changes nothing.
    fn command(&mut self, c: Command) -> Result<()> {
        let before = self.state();
        let label = c.label();
        match self.edit(Edit::Command(c))? {
            Edited::Command(_, Ok(_), _) => Ok(()),
            Edited::Command(_, Err(e), _) => {
                self.report.refused += 1;
                ensure!(
                    self.state() == before,
                    "{label} was refused ({e}) but changed the document"
                );
                Ok(())
            }
            _ => bail!("{label}: an unexpected answer from the edit thread"),
        }
    }

    fn materials(&self) -> u64 {
        self.doc
            .read()
            .unwrap_or_else(|p| p.into_inner())
            .scene
            .world
            .materials()
            .len() as u64
    }

    fn point(&mut self) -> DVec3 {
        let s = self.opts.size.as_dvec3();
        DVec3::new(
            self.rng.unit() * s.x,
            self.rng.unit() * s.y,
            self.rng.unit() * s.z,
        )
    }

    fn voxel(&mut self) -> IVec3 {
        self.point().floor().as_ivec3()
    }

    /// A box of up to `side` voxels per axis, now and then reaching out of the grid.
    fn box_corners(&mut self, side: i64) -> (IVec3, IVec3) {
        let a = self.voxel() - IVec3::splat(2);
        let d = IVec3::new(
            self.rng.range(0, side) as i32,
            self.rng.range(0, side) as i32,
            self.rng.range(0, side) as i32,
        );
        (a, a + d)
    }

    fn stroke(&mut self) -> Result<()> {
        let shape = self.rng.pick(&[
            BrushShape::Voxel,
            BrushShape::Sphere,
            BrushShape::Cube,
            BrushShape::Cylinder,
            BrushShape::Line,
            BrushShape::Box,
        ]);
        let mode = self
            .rng
            .pick(&[BrushMode::Attach, BrushMode::Erase, BrushMode::Paint]);
        let m = self.rng.chance(0.3);
        // A colour mode now and then (darken with attach, a material past the table: refused).
        let paint = match self.rng.below(10) {
            0 => PaintMode::Gradient {
                to: self.rng.below(self.materials() + 1) as u8,
            },
            1 => PaintMode::Random {
                among: (0..self.rng.below(4))
                    .map(|_| self.rng.below(self.materials() + 1) as u8)
                    .collect(),
                seed: self.rng.below(1 << 32) as u32,
            },
            2 => PaintMode::Darken,
            3 => PaintMode::Brighten,
            _ => PaintMode::Solid,
        };
        let stroke = Stroke {
            mode,
            shape,
            size: if self.rng.chance(0.05) {
                self.rng.range(8, 16) as f64
            } else {
                self.rng.range(1, 5) as f64 + self.rng.unit()
            },
            material: self.rng.below(self.materials() + 1) as u8,
            mirror: Mirror {
                x: m && self.rng.chance(0.7),
                y: m && self.rng.chance(0.3),
                z: m && self.rng.chance(0.5),
                centre: self.point(),
            },
            points: vec![self.point()],
            axis: self.rng.pick(&[Axis::X, Axis::Y, Axis::Z]),
            in_selection: self.rng.chance(0.1),
            paint,
        };
        let before = self.state();
        let mut at = stroke.points[0];
        *self.report.kinds.entry("stroke begin").or_default() += 1;
        match self.edit(Edit::StrokeBegin(stroke))? {
            Edited::Stroke(Ok(_)) => {}
            Edited::Stroke(Err(e)) => {
                self.report.refused += 1;
                ensure!(
                    self.state() == before,
                    "a refused stroke ({e}) changed the document"
                );
                return Ok(());
            }
            _ => bail!("stroke begin: an unexpected answer"),
        }
        // Points as a drag makes them: mostly small steps, now and then a leap (a fast drag
        // on a slow frame).
        for _ in 0..self.rng.below(24) {
            let step = if self.rng.chance(0.15) { 40.0 } else { 3.0 };
            at += DVec3::new(
                (self.rng.unit() - 0.5) * step,
                (self.rng.unit() - 0.5) * step * 0.3,
                (self.rng.unit() - 0.5) * step,
            );
            *self.report.kinds.entry("stroke point").or_default() += 1;
            match self.edit(Edit::StrokeExtend(vec![at]))? {
                Edited::Stroke(Ok(_)) => {}
                Edited::Stroke(Err(e)) => {
                    // A failing segment undoes the whole stroke.
                    self.report.refused += 1;
                    ensure!(
                        self.state() == before,
                        "a failed stroke segment ({e}) left part of the stroke"
                    );
                    return Ok(());
                }
                _ => bail!("stroke point: an unexpected answer"),
            }
        }
        if self.rng.chance(0.08) {
            *self.report.kinds.entry("stroke cancel").or_default() += 1;
            let _ = self.edit(Edit::StrokeAbort)?;
            ensure!(
                self.state() == before,
                "a cancelled stroke left something behind"
            );
        } else {
            *self.report.kinds.entry("stroke end").or_default() += 1;
            if let Edited::Stroke(Err(e)) = self.edit(Edit::StrokeEnd)? {
                self.report.refused += 1;
                ensure!(
                    self.state() == before,
                    "a refused stroke end ({e}) changed the document"
                );
            }
        }
        Ok(())
    }

    fn undo_redo_burst(&mut self) -> Result<()> {
        let n = self.rng.range(1, 30);
        for _ in 0..n {
            let undo = self.rng.chance(0.6);
            *self
                .report
                .kinds
                .entry(if undo { "undo" } else { "redo" })
                .or_default() += 1;
            let before = self.state();
            let result = self.edit(if undo { Edit::Undo } else { Edit::Redo })?;
            match result {
                Edited::Undo(Err(_)) | Edited::Redo(Err(_)) => {
                    ensure!(
                        self.state() == before,
                        "a refused undo / redo changed the document"
                    )
                }
                Edited::Undo(Ok(_)) | Edited::Redo(Ok(_)) => {}
                _ => bail!("undo / redo: an unexpected answer"),
            }
        }
        Ok(())
    }

    fn random_command(&mut self) -> Command {
        let materials = self.materials();
        let m = |r: &mut Rng| r.below(materials + 1) as u8;
        match self.rng.below(22) {
            0 => {
                let (min, max) = self.box_corners(24);
                Command::Select(SelectOp::Replace { min, max })
            }
            1 => {
                let (min, max) = self.box_corners(16);
                Command::Select(SelectOp::Add { min, max })
            }
            2 => {
                let (min, max) = self.box_corners(16);
                Command::Select(SelectOp::Subtract { min, max })
            }
            3 => Command::Select(if self.rng.chance(0.5) {
                SelectOp::All
            } else {
                SelectOp::None
            }),
            4 => Command::DeleteSelection,
            5 => Command::FillSelection(m(&mut self.rng)),
            6 => Command::PaintSelection(m(&mut self.rng)),
            7 if self.rng.chance(0.3) => {
                use crate::selection_transform::SelectionTransform;
                use brickmap::objects::Axis as Turn;
                let axis = self.rng.pick(&[Turn::X, Turn::Y, Turn::Z]);
                Command::TransformSelection(if self.rng.chance(0.3) {
                    SelectionTransform::Flip(axis)
                } else {
                    SelectionTransform::Turn {
                        axis,
                        quarters: self.rng.range(-2, 2) as i32,
                    }
                })
            }
            7 => Command::MoveSelection(IVec3::new(
                self.rng.range(-9, 9) as i32,
                self.rng.range(-3, 3) as i32,
                self.rng.range(-9, 9) as i32,
            )),
            8 => Command::Copy,
            9 => Command::Cut,
            10 => Command::Paste { at: self.voxel() },
            11 => Command::SetColour {
                index: self.rng.below(256) as u8,
                rgb: [
                    self.rng.below(256) as u8,
                    self.rng.below(256) as u8,
                    self.rng.below(256) as u8,
                ],
            },
            12 => Command::AddMaterial(self.material_spec()),
            13 => Command::SetMaterial {
                index: m(&mut self.rng),
                material: self.material_spec(),
            },
            14 => Command::SetParam {
                kind: self
                    .rng
                    .pick(&[KindSpec::Metal, KindSpec::Dielectric, KindSpec::Emissive]),
                index: self.rng.below(64) as u8,
                value: (self.rng.unit() * 3.0 - 0.5) as f32,
            },
            15 => Command::RemoveUnusedMaterials,
            16 => Command::FloodFill {
                start: self.voxel(),
                material: m(&mut self.rng),
            },
            17 => {
                let d = self.doc.read().unwrap_or_else(|p| p.into_inner());
                let mut camera = d.scene.params.camera.clone();
                drop(d);
                camera.yaw_deg += (self.rng.unit() - 0.5) * 90.0;
                camera.pitch_deg = (self.rng.unit() - 0.5) * 170.0;
                camera.position += DVec3::new(
                    (self.rng.unit() - 0.5) * 20.0,
                    (self.rng.unit() - 0.5) * 10.0,
                    (self.rng.unit() - 0.5) * 20.0,
                );
                Command::SetCamera(camera)
            }
            18 => {
                let d = self.doc.read().unwrap_or_else(|p| p.into_inner());
                let mut sun = d.scene.params.sun.clone();
                drop(d);
                sun.enabled = self.rng.chance(0.8);
                sun.intensity = (self.rng.unit() * 20.0) as f32;
                sun.radius = 1.0 + self.rng.unit() * 10.0;
                Command::SetSun(sun)
            }
            19 => Command::SetSky(render::Sky::Gradient {
                horizon: [self.rng.unit() as f32, self.rng.unit() as f32, 0.6],
                zenith: [0.2, 0.4, self.rng.unit() as f32],
            }),
            20 => {
                let d = self.doc.read().unwrap_or_else(|p| p.into_inner());
                let mut s = d.scene.params.settings.clone();
                drop(d);
                s.max_bounces = self.rng.range(0, 6) as u32;
                Command::SetSettings(s)
            }
            _ => Command::GenerateTerrain(TerrainSpec {
                seed: self.rng.next() as u32,
                scale: 10.0 + self.rng.unit() * 60.0,
                octaves: self.rng.range(1, 6) as u32,
                height_range: (1, (self.opts.size.y - 1).max(2)),
                water_level: self.rng.below(u64::from(self.opts.size.y / 2)) as u32,
                noise: Default::default(),
                bands: Default::default(),
            }),
        }
    }

    fn material_spec(&mut self) -> MaterialSpec {
        MaterialSpec {
            kind: self.rng.pick(&[
                KindSpec::Lambertian,
                KindSpec::Metal,
                KindSpec::Dielectric,
                KindSpec::Emissive,
            ]),
            param: self.rng.below(66) as u8,
            colour: self.rng.below(256) as u8,
        }
    }

    /// Saves the document, reloads it and checks the hash; with `reopen`, the reloaded scene
    /// replaces the document (the history starts over, as after File → Open).
    fn save_and_reload(&mut self, reopen: bool) -> Result<()> {
        let name = format!("soak-{}.ron", self.opts.seed);
        let path = self.opts.out_dir.join(&name);
        let before = hash(&self.doc);
        {
            let mut d = self.doc.write().unwrap_or_else(|p| p.into_inner());
            d.save(&path).context("saving")?;
        }
        let scene = crate::formats::load(&path, self.opts.workers).context("reloading the save")?;
        let loaded = scene.world.read().content_hash();
        ensure!(
            loaded == before,
            "the reloaded save's hash {loaded:016x} is not the document's {before:016x}"
        );
        if reopen {
            let mut d = self.doc.write().unwrap_or_else(|p| p.into_inner());
            let mut recorder = d.recorder.take();
            if let Some(r) = &mut recorder {
                r.record(Step::Open(name));
            }
            let mut next = Document::new(scene, History::with_budget(self.opts.history_budget));
            next.folder = self.opts.out_dir.clone();
            next.recorder = recorder;
            *d = next;
            drop(d);
            self.opening = loaded;
            if let Some(vp) = &mut self.viewport {
                let ctx = vp.ctx().clone();
                vp.wait_idle()?;
                let d = self.doc.read().unwrap_or_else(|p| p.into_inner());
                *vp = Viewport::new(ctx, &d.scene.world.read())?;
            }
        }
        Ok(())
    }

    /// Undo of the whole history gives the opening hash, redo the latest; save and reload.
    fn check(&mut self) -> Result<()> {
        let now = hash(&self.doc);
        let (undo, dropped) = {
            let d = self.doc.read().unwrap_or_else(|p| p.into_inner());
            (d.history.undo_len(), d.history.dropped())
        };
        for _ in 0..undo {
            if let Edited::Undo(Err(e)) = self.edit(Edit::Undo)? {
                bail!("undoing the whole history: {e}");
            }
        }
        let back = hash(&self.doc);
        if dropped == 0 {
            ensure!(
                back == self.opening,
                "undo of all {undo} steps gives {back:016x}, not the opening {:016x}",
                self.opening
            );
        }
        for _ in 0..undo {
            if let Edited::Redo(Err(e)) = self.edit(Edit::Redo)? {
                bail!("redoing the whole history: {e}");
            }
        }
        let again = hash(&self.doc);
        ensure!(
            again == now,
            "redo of all {undo} steps gives {again:016x}, not {now:016x}"
        );
        self.save_and_reload(false)?;
        let (history, world) = {
            let d = self.doc.read().unwrap_or_else(|p| p.into_inner());
            let m = d.scene.world.read().memory();
            (d.history.bytes(), m.gpu_reserved() + m.cpu_only)
        };
        ensure!(
            history <= self.opts.history_budget,
            "the history holds {history} bytes, over its bound {}",
            self.opts.history_budget
        );
        let resident = rss();
        self.report.peak_history = self.report.peak_history.max(history);
        self.report.peak_rss = self.report.peak_rss.max(resident);
        let allowed = self.baseline_rss + self.opts.history_budget as u64 + 4 * world + (512 << 20);
        ensure!(
            resident == 0 || resident <= allowed,
            "resident memory {resident} bytes, over the history bound + the world + 512 MiB ({allowed})"
        );
        self.report.checks += 1;
        Ok(())
    }

    /// A frame of the live viewport at the current size, then the validation count.
    fn frame(&mut self) -> Result<()> {
        let Some(vp) = &mut self.viewport else {
            return Ok(());
        };
        let d = self.doc.read().unwrap_or_else(|p| p.into_inner());
        let req = FrameRequest {
            params: &d.scene.params,
            internal: self.view_size,
            output: self.view_size,
            spp: 1,
            target_spp: 1 << 20,
            exposure: 0.0,
            bgra: false,
            denoise: self.rng.chance(0.2),
            reproject: true,
            dim: None,
            grid: None,
        };
        // A slot comes free when an earlier frame finishes: on a loaded CPU driver that can
        // take seconds, so wait by time, not by tries.
        let mut drawn = false;
        let waiting = std::time::Instant::now();
        while waiting.elapsed() < Duration::from_secs(300) {
            if vp.try_draw(&d.scene.world, &req)?.is_some() {
                drawn = true;
                break;
            }
            std::thread::sleep(Duration::from_micros(200));
        }
        drop(d);
        ensure!(drawn, "no frame slot came free in 300 s");
        self.report.frames += 1;
        self.report.inputs += 1;
        let errors = vp.ctx().validation_errors();
        ensure!(errors == 0, "{errors} Vulkan validation errors");
        Ok(())
    }

    /// One event; false when the session is over.
    fn event(&mut self) -> Result<()> {
        let kind = self.rng.below(100);
        match kind {
            0..=34 => self.stroke()?,
            35..=44 => self.undo_redo_burst()?,
            45..=46 => {
                *self.report.kinds.entry("resize").or_default() += 1;
                self.report.inputs += 1;
                self.view_size = (
                    self.rng.range(8, i64::from(self.opts.view.0)) as u32,
                    self.rng.range(8, i64::from(self.opts.view.1)) as u32,
                );
            }
            47 => {
                *self.report.kinds.entry("save and reopen").or_default() += 1;
                let reopen = self.rng.chance(0.5);
                self.save_and_reload(reopen)?;
            }
            _ => {
                let c = self.random_command();
                let kind = match &c {
                    Command::Select(_) => "select",
                    Command::DeleteSelection
                    | Command::FillSelection(_)
                    | Command::PaintSelection(_)
                    | Command::MoveSelection(_)
                    | Command::TransformSelection(_) => "selection operation",
                    Command::Copy | Command::Cut | Command::Paste { .. } => "clipboard",
                    Command::SetColour { .. }
                    | Command::AddMaterial(_)
                    | Command::SetMaterial { .. }
                    | Command::SetParam { .. }
                    | Command::RemoveUnusedMaterials => "palette and materials",
                    Command::FloodFill { .. } => "flood fill",
                    Command::GenerateTerrain(_) => "terrain",
                    _ => "camera, sun, sky, settings",
                };
                *self.report.kinds.entry(kind).or_default() += 1;
                self.command(c)?;
            }
        }
        Ok(())
    }

    /// The recorded session as a replay script.
    fn script(&self) -> String {
        let d = self.doc.read().unwrap_or_else(|p| p.into_inner());
        d.recorder
            .as_ref()
            .map(|r| r.to_ron(self.start.clone(), Some(self.opts.workers)))
            .unwrap_or_default()
    }
}

impl super::Driver for Session {
    fn start(opts: &SoakOptions) -> Result<Self> {
        Self::new(opts)
    }

    fn event(&mut self, n: u64) -> Result<()> {
        self.event()?;
        if n.is_multiple_of(self.opts.frame_every.max(1)) {
            self.frame()?;
        }
        Ok(())
    }

    fn check(&mut self) -> Result<()> {
        self.check()
    }

    fn report(&mut self) -> &mut SoakReport {
        &mut self.report
    }

    fn script(&self) -> String {
        self.script()
    }

    fn finish(&mut self) -> Result<()> {
        if let Some(vp) = &mut self.viewport {
            vp.wait_idle()?;
        }
        Ok(())
    }
}
