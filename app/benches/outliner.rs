//! The Objects window with 10,000 objects (one shared 8³ model, in 100 groups of 100): the
//! CPU time of one egui frame that lays it out (scrolled to the top), and
//! of a frame without it (the difference is the window's cost).
//!
//! Run: `cargo bench -p app --bench outliner`.

use app::editor::Document;
use app::editor::history::History;
use app::scene::Scene;
use app::ui::outliner::{OutlinerState, draw};
use brickmap::objects::{LayerId, Model, ModelId, NewNode, ObjectTree, Objects, Placement};
use brickmap::{EditOp, GridDims, Mode, Shape, World, WorldConfig};
use divan::Bencher;
use glam::IVec3;

fn main() {
    divan::main();
}

fn document() -> Document {
    let world = World::new(
        GridDims::new(32, 4, 32).unwrap(),
        WorldConfig::with_workers(0),
    )
    .unwrap();
    let table = world.materials().clone();
    let mut model = Model::new(IVec3::splat(8)).unwrap();
    let fill = EditOp::Shape {
        shape: Shape::Box {
            min: IVec3::ZERO,
            max: IVec3::splat(7),
        },
        mode: Mode::Add(0),
    };
    model.apply(&fill, &table).unwrap();
    let mut tree = ObjectTree::new();
    let object = NewNode::Object {
        model: ModelId(0),
        layer: LayerId(0),
    };
    for g in 0..100 {
        let group = tree
            .add(
                ObjectTree::ROOT,
                None,
                format!("row {g}"),
                Placement::IDENTITY,
                NewNode::Group,
            )
            .unwrap();
        for k in 0..100 {
            let at = Placement::at(IVec3::new(k * 2 + 4, 4, g * 2 + 4));
            tree.add(group, None, format!("block {g}.{k}"), at, object)
                .unwrap();
        }
    }
    let models = std::collections::BTreeMap::from([(ModelId(0), model)]);
    let objects = Objects::new(tree, models, &world).unwrap();
    let params = render::SceneParams::framing(world.dims().voxels().as_dvec3());
    let active = Scene::first_object(&objects);
    Document::new(
        Scene::with_objects(world, objects, active, params),
        History::default(),
    )
}

fn frame(ctx: &egui::Context, doc: &Document, mut state: Option<&mut OutlinerState>) -> usize {
    let raw = egui::RawInput {
        screen_rect: Some(egui::Rect::from_min_size(
            egui::Pos2::ZERO,
            egui::vec2(1920.0, 1080.0),
        )),
        ..Default::default()
    };
    let mut out = Vec::new();
    let area = egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(1920.0, 1080.0));
    let full = ctx.run_ui(raw, |ui| {
        if let Some(state) = state.as_deref_mut() {
            draw(ui.ctx(), area, state, doc, &mut out);
        }
    });
    full.shapes.len() + out.len()
}

#[divan::bench(sample_count = 30)]
fn a_frame_with_the_window(bencher: Bencher) {
    let doc = document();
    let ctx = egui::Context::default();
    let mut state = OutlinerState {
        open: true,
        ..Default::default()
    };
    frame(&ctx, &doc, Some(&mut state));
    bencher.bench_local(|| frame(&ctx, &doc, Some(&mut state)));
}

#[divan::bench(sample_count = 30)]
fn a_frame_without_it(bencher: Bencher) {
    let doc = document();
    let ctx = egui::Context::default();
    frame(&ctx, &doc, None);
    bencher.bench_local(|| frame(&ctx, &doc, None));
}
