//! The real editor driven by the mouse and keyboard (xdotool under Xvfb, lavapipe, validation
//! on), waiting for the editor's handshake log (`VOXBRICK_REPORT`) after every input instead
//! of sleeping: mouse strokes, keys and selections replay headlessly to the saved scene; a
//! drag whose moves arrive faster than frames is one connected stroke that reaches the release
//! point; an editor killed after an autosave offers it on the next start, and recovering gives
//! the autosaved content; objects are picked and turned in arrange mode, duplicated and
//! reordered in the Objects window (found by the `widget` lines of the log) and edited. Without Xvfb, xdotool or a Vulkan driver the tests skip, saying so,
//! unless VOXBRICK_REQUIRE_GPU=1 (CI) makes that a failure.

mod input;
mod window;

use std::collections::{BTreeSet, HashSet};
use std::path::Path;

use input::session::*;
use input::shot::Shot;
use window::scratch;

#[test]
fn strokes_drawn_with_the_mouse_replay_headlessly_to_the_same_scene() {
    let Some(x) = tools_ready() else { return };
    let dir = scratch("strokes");
    let (work, session) = (dir.join("work.ron"), dir.join("session.ron"));
    // Big enough that the viewport between the docks holds every point below.
    let Some(mut s) = Session::recorded(&x, &dir, "960x540") else {
        return;
    };
    // A click that closes a menu draws nothing.
    s.mouse_to((20, 11));
    s.press();
    s.release();
    s.report.frame();
    s.drag(&[(480, 220)], None);
    s.report.frame();
    // Attach, paint, undo, redo, erase.
    let stroke = Some("edited stroke end");
    s.drag(
        &[(480, 220), (490, 230), (500, 230), (510, 230), (520, 230)],
        stroke,
    );
    s.key("p", "KeyP", "input key Code(KeyP) down");
    s.drag(&[(450, 300), (470, 300), (490, 310)], stroke);
    s.key("ctrl+z", "KeyZ", "edited history: ok");
    s.key("ctrl+shift+z", "KeyZ", "edited history: ok");
    s.key("x", "KeyX", "input key Code(KeyX) down");
    s.drag(&[(560, 260), (565, 262)], stroke);
    // Selection: a box, copy, move it, paste the copy elsewhere, fill the pasted region.
    s.key("m", "KeyM", "input key Code(KeyM) down");
    s.drag(
        &[(430, 250), (450, 260), (470, 270)],
        Some("edited command Select"),
    );
    s.key("ctrl+c", "KeyC", "edited command Copy");
    s.key("Right", "ArrowRight", "edited command");
    s.key("ctrl+v", "KeyV", "input key Code(KeyV) down");
    // Low on the terrain: a paste on a column that reaches the ceiling would be outside.
    s.mouse_to((450, 440));
    s.press();
    // The paste lands at the press; its line may come before or after the release's.
    let mark = s.report.position();
    s.release();
    s.report.set_position(mark);
    s.report
        .wait("the paste", |l| l.starts_with("edited command Paste"));
    s.key("ctrl+f", "KeyF", "edited command");
    s.key("ctrl+s", "KeyS", "saved ");
    let out = s.quit();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "the editor (validation on) failed: {stderr}"
    );
    assert!(!stderr.contains("vulkan "), "validation messages: {stderr}");
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
    window::replay(env!("CARGO_BIN_EXE_voxbrick"), &session, &replayed);
    let saved = hash(&work);
    assert_ne!(
        saved,
        hash(&dir.join("session-start.ron")),
        "the session changed the scene"
    );
    assert_eq!(saved, hash(&replayed.join("work.ron")));
}

/// The solid voxels of a scene file.
fn solid(path: &Path) -> HashSet<(i32, i32, i32)> {
    let scene = app::formats::load(path, 1).unwrap();
    let view = scene.world.read();
    let v = view.dims().voxels();
    let mut out = HashSet::new();
    for x in 0..v.x {
        for y in 0..v.y {
            for z in 0..v.z {
                if view.voxel(glam::IVec3::new(x, y, z)).unwrap().is_some() {
                    out.insert((x, y, z));
                }
            }
        }
    }
    out
}

/// The 26-connected pieces of a voxel set.
fn components(set: &BTreeSet<(i32, i32, i32)>) -> usize {
    let mut v = brickmap::VoxelSet::new();
    for &(x, y, z) in set {
        v.insert(glam::IVec3::new(x, y, z));
    }
    v.components()
}

fn voxel_of(line: &str) -> (i32, i32, i32) {
    let w: Vec<i32> = line
        .rsplit(' ')
        .take(3)
        .map(|t| t.parse().unwrap())
        .collect();
    (w[2], w[1], w[0])
}

#[test]
fn a_drag_faster_than_the_frames_is_one_connected_stroke_reaching_the_release_point() {
    let Some(x) = tools_ready() else { return };
    let dir = scratch("fast-drag");
    let (work, session) = (dir.join("work.ron"), dir.join("session.ron"));
    let Some(mut s) = Session::recorded(&x, &dir, "960x540") else {
        return;
    };
    // The thinnest brush: the voxel, one voxel per point.
    s.key("v", "KeyV", "input key Code(KeyV) down");
    // From the viewport's left part (x 236 to 724 between the docks) across 340 px.
    let (x0, y) = (260, 300);
    s.mouse_to((x0, y));
    s.press();
    // 30 moves across 300 px in one xdotool call (far faster than lavapipe's frames), the
    // last one a longer step, then the release.
    let mut moves: Vec<(i32, i32)> = (1..=29).map(|k| (x0 + 10 * k, y)).collect();
    moves.push((x0 + 340, y + 5));
    let mut args: Vec<String> = Vec::new();
    for (mx, my) in &moves {
        args.extend(["mousemove".into(), mx.to_string(), my.to_string()]);
    }
    args.extend(["mouseup".into(), "1".into()]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    s.xdotool(&args);
    s.report
        .wait("the stroke", |l| l.starts_with("edited stroke end"));
    let lines = s.report.lines();
    s.key("ctrl+s", "KeyS", "saved ");
    let out = s.quit();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // Every move was handled, in order, and the release came after the last.
    let handled: Vec<&String> = lines
        .iter()
        .filter(|l| l.starts_with("input move ") || l.as_str() == "input release Left")
        .collect();
    let tail: Vec<String> = moves
        .iter()
        .map(|(mx, my)| format!("input move {mx} {my}"))
        .chain(["input release Left".to_string()])
        .collect();
    assert!(
        handled.len() >= tail.len()
            && handled[handled.len() - tail.len()..]
                .iter()
                .zip(&tail)
                .all(|(a, b)| *a == b),
        "the moves were not all handled in order: {handled:?}"
    );
    let release = lines
        .iter()
        .find(|l| l.starts_with("stroke release "))
        .expect("the release ended the stroke");
    let (rx, ry) = moves[moves.len() - 1];
    assert!(
        release.starts_with(&format!("stroke release {rx} {ry} voxel ")),
        "{release}"
    );
    let points = lines
        .iter()
        .filter(|l| l.starts_with("stroke point "))
        .count();
    assert!(points >= 10, "{points} stroke points from 30 moves");
    // The stroke the editor made from those events (as recorded), drawn alone into the
    // emptied scene (the terrain it was drawn over hides voxels it left as they were): one
    // 26-connected piece from the press to the release point.
    let script = app::editor::script::parse(&std::fs::read_to_string(&session).unwrap()).unwrap();
    let strokes: Vec<&app::editor::command::Stroke> = script
        .steps
        .iter()
        .filter_map(|s| match s {
            app::editor::script::Step::Do(app::editor::command::Command::Stroke(s)) => Some(s),
            _ => None,
        })
        .collect();
    assert_eq!(strokes.len(), 1, "one stroke recorded");
    assert!(
        strokes[0].points.len() > points,
        "every point is in the stroke"
    );
    let alone = dir.join("alone.ron");
    let mut doc = app::editor::Document::new(
        app::formats::load(&work, 1).unwrap(),
        app::editor::history::History::default(),
    );
    doc.execute(app::editor::command::Command::Clear).unwrap();
    doc.execute(app::editor::command::Command::Stroke(strokes[0].clone()))
        .unwrap();
    app::formats::save(&doc.scene, &alone).unwrap();
    let added: BTreeSet<(i32, i32, i32)> = solid(&alone).into_iter().collect();
    assert!(added.len() >= points, "{} voxels added", added.len());
    assert_eq!(components(&added), 1, "the stroke is in pieces");
    assert!(
        added.contains(&voxel_of(release)),
        "the stroke does not reach the release point: {release}"
    );
    let begin = lines
        .iter()
        .find(|l| l.starts_with("stroke begin "))
        .unwrap();
    assert!(added.contains(&voxel_of(begin)), "{begin}");
}

/// Both modes and the Objects window, by mouse and keys: Tab, a click picks the terrain
/// object, Alt + Y turns it; View → Objects, Duplicate, the copy dragged above the original
/// (reordered), a double-click on the original edits it (the brush again) and a stroke
/// draws on it. The saved project holds both objects in the new order, and the recorded
/// session replays headlessly to the same scene.
#[test]
fn objects_are_arranged_in_the_viewport_and_the_objects_window_and_edited() {
    let Some(x) = tools_ready() else { return };
    let dir = scratch("objects");
    let (work, session) = (dir.join("work.ron"), dir.join("session.ron"));
    let Some(mut s) = Session::recorded(&x, &dir, "960x540") else {
        return;
    };
    s.key("Tab", "Tab", "input key Code(Tab) down");
    s.click((480, 300));
    s.report.frame();
    s.key("alt+y", "KeyY", "edited command Turn #1 90° about Y: ok");
    let view = s.widget("View");
    s.click(view);
    let objects = s.widget("Objects");
    s.click(objects);
    let duplicate = s.widget("Duplicate");
    s.click(duplicate);
    s.report.wait("the copy", |l| {
        l.starts_with("edited command Duplicate #1: ok")
    });
    // The copy's row dragged onto the upper part of the original's: it goes before it.
    let original = s.widget("scene");
    let copy = s.widget("scene copy");
    let steps: Vec<(i32, i32)> = (0..=6)
        .map(|k| (copy.0, copy.1 + (original.1 - 4 - copy.1) * k / 6))
        .collect();
    s.drag(&steps, Some("edited command Move #2 into #0: ok"));
    // A double-click on the original's row: edit its voxels with the brush.
    let original = s.widget("scene");
    s.double_click(original, "editing scene (Tab: arrange)");
    s.report.frame();
    s.drag(
        &[(640, 420), (650, 425), (660, 430)],
        Some("edited stroke end"),
    );
    s.key("ctrl+s", "KeyS", "saved ");
    s.quit_cleanly();
    let text = std::fs::read_to_string(&session).expect("the session was recorded");
    for what in ["Turn(", "Duplicate(", "Reparent(", "Stroke("] {
        assert!(text.contains(what), "{what} missing:\n{text}");
    }
    // The saved tree: the copy first, then the original, which the stroke changed.
    let scene = app::formats::load(&work, 1).unwrap();
    let objects = scene.objects();
    let tree = objects.tree();
    let names: Vec<&str> = tree
        .node(brickmap::objects::ObjectTree::ROOT)
        .unwrap()
        .children()
        .iter()
        .map(|c| tree.node(*c).unwrap().name.as_str())
        .collect();
    assert_eq!(names, ["scene copy", "scene"]);
    let solid = |name: &str| {
        tree.subtree(brickmap::objects::ObjectTree::ROOT)
            .unwrap()
            .into_iter()
            .find_map(|n| match tree.node(n).unwrap() {
                node if node.name != name => None,
                node => match node.kind {
                    brickmap::objects::NodeKind::Object { model, .. } => {
                        Some(objects.model(model).unwrap().solid_count())
                    }
                    _ => None,
                },
            })
            .unwrap()
    };
    assert_ne!(
        solid("scene"),
        solid("scene copy"),
        "the stroke drew on one"
    );
    let replayed = dir.join("replayed");
    window::replay(env!("CARGO_BIN_EXE_voxbrick"), &session, &replayed);
    assert_eq!(hash(&work), hash(&replayed.join("work.ron")));
}

/// The modelling tools by mouse and keys: U and a drag up a face extrudes it; M, "wand:
/// colour" and a click select the connected voxels of a material; Alt + Y turns them about
/// their centre. The recorded session replays headlessly to the saved project.
#[test]
fn a_face_is_extruded_a_wand_selects_and_the_selection_turns() {
    let Some(x) = tools_ready() else { return };
    let dir = scratch("modelling");
    let (work, session) = (dir.join("work.ron"), dir.join("session.ron"));
    let Some(mut s) = Session::recorded(&x, &dir, "960x540") else {
        return;
    };
    s.key("u", "KeyU", "input key Code(KeyU) down");
    let up: Vec<(i32, i32)> = (0..=6).map(|k| (480, 300 - 8 * k)).collect();
    s.drag(&up, Some("edited command Extrude the face at"));
    s.key("m", "KeyM", "input key Code(KeyM) down");
    let wand = s.widget("wand: colour");
    s.click(wand);
    // The wand selects at the press: its line may come before the release's.
    let mark = s.report.position();
    s.click((480, 340));
    s.report.set_position(mark);
    s.report.wait("the wand", |l| {
        l.starts_with("edited command Magic wand at")
    });
    s.key(
        "alt+y",
        "KeyY",
        "edited command Turn selection 90° about Y: ok",
    );
    s.key("ctrl+s", "KeyS", "saved ");
    s.quit_cleanly();
    let text = std::fs::read_to_string(&session).expect("the session was recorded");
    for what in ["Extrude(", "Wand(", "TransformSelection("] {
        assert!(text.contains(what), "{what} missing:\n{text}");
    }
    let replayed = dir.join("replayed");
    window::replay(env!("CARGO_BIN_EXE_voxbrick"), &session, &replayed);
    assert_eq!(hash(&work), hash(&replayed.join("work.ron")));
}

#[test]
fn a_killed_editor_offers_its_autosave_and_recovering_gives_its_content() {
    let Some(x) = tools_ready() else { return };
    let dir = scratch("killed");
    let work = dir.join("work.ron");
    new_terrain(&work, "64x32x64");
    let config = dir.join("config");
    std::fs::create_dir_all(&config).unwrap();
    std::fs::write(config.join("settings.ron"), "(autosave_secs: 1)").unwrap();
    let recovery = config.join("recovery.ron");
    let Some(mut s) = Session::start(
        &x,
        &dir,
        &config,
        &[work.to_str().unwrap(), "--window", "960x540"],
    ) else {
        return;
    };
    s.report.wait("the file", |l| l.starts_with("loaded "));
    s.drag(
        &[(480, 220), (500, 230), (520, 230)],
        Some("edited stroke end"),
    );
    // The autosave after the stroke, then a kill that gives the editor no chance.
    s.report
        .wait("the autosave", |l| l.starts_with("autosaved "));
    s.kill();
    assert!(recovery.exists(), "the autosave is on disk");
    let autosaved = hash(&recovery);
    assert_ne!(autosaved, hash(&work), "the autosave holds the stroke");

    // The next start offers it; Enter recovers it.
    let Some(mut s) = Session::start(&x, &dir, &config, &["--window", "960x540"]) else {
        return;
    };
    let lines = s.report.lines();
    assert!(
        lines.iter().any(|l| l.starts_with("offered recovery ")),
        "{lines:?}"
    );
    s.mouse_to((320, 200));
    s.key("Return", "Enter", "loaded recovery hash ");
    let line = s
        .report
        .lines()
        .into_iter()
        .find(|l| l.starts_with("loaded recovery hash "))
        .unwrap();
    assert_eq!(
        line,
        format!("loaded recovery hash {autosaved:016x}"),
        "the recovered scene is the autosaved one"
    );
    s.kill();
}

#[test]
fn the_docks_leave_the_viewport_where_f_frames_the_scene_and_the_palette_shows() {
    let Some(x) = tools_ready() else { return };
    let dir = scratch("layout");
    let Some(mut s) = Session::recorded(&x, &dir, "960x540") else {
        return;
    };
    s.mouse_to((480, 270));
    s.key("f", "KeyF", "input key Code(KeyF) down");
    // The framed view converged a little (a few frames after the key).
    for _ in 0..4 {
        s.report.frame();
    }
    let line = s
        .report
        .lines()
        .into_iter()
        .rev()
        .find(|l| l.starts_with("viewport "))
        .expect("the editor reports its viewport");
    let v: Vec<u32> = line[9..].split(' ').map(|n| n.parse().unwrap()).collect();
    let (vx, vy, vw, vh) = (v[0], v[1], v[2], v[3]);
    assert!(
        vx > 100 && vx + vw < 860 && vw > 400,
        "docks on both sides: {line}"
    );
    let shot = Shot::take(&x.display);
    // The palette: the right dock shows the 256 colours (many distinct ones).
    let mut colours = std::collections::HashSet::new();
    for py in (vy + 50..vy + 360).step_by(3) {
        for px in (vx + vw + 8..952).step_by(3) {
            colours.insert(shot.rgb(px, py));
        }
    }
    assert!(
        colours.len() > 100,
        "the palette shows {} colours",
        colours.len()
    );
    // F framed the scene inside the viewport: grass inside, none on its border.
    let inside = (vy + vh / 4..vy + 3 * vh / 4)
        .step_by(4)
        .flat_map(|py| {
            (vx + vw / 4..vx + 3 * vw / 4)
                .step_by(4)
                .map(move |px| (px, py))
        })
        .filter(|&(px, py)| shot.grass(px, py))
        .count();
    assert!(
        inside > 100,
        "the terrain shows in the viewport ({inside} grass samples)"
    );
    let border: Vec<(u32, u32)> = (vy + 2..vy + vh - 2)
        .flat_map(|py| [(vx + 2, py), (vx + vw - 3, py)])
        .chain((vx + 2..vx + vw - 2).flat_map(|px| [(px, vy + 2), (px, vy + vh - 3)]))
        .filter(|&(px, py)| shot.grass(px, py))
        .collect();
    assert!(
        border.is_empty(),
        "the framed scene reaches the viewport's edge at {:?}",
        &border[..border.len().min(8)]
    );
    let out = s.quit();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
