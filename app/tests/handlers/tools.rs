//! The modelling tools driven as a user does: the Stamp tool along a drag, the brush's
//! colour modes chosen in the Tools panel.

use super::session::Session;
use app::editor::command::{Command, PaintMode};
use winit::event::MouseButton;
use winit::keyboard::KeyCode;

fn tap(s: &mut Session, code: KeyCode) {
    s.key(code, true);
    s.key(code, false);
    s.quiet();
}

/// Copy a small box of the terrain, J, H (a quarter turn), a drag across the terrain: one
/// step with a stamp every stamp's width, nothing before the release, undone exactly.
pub fn the_stamp_puts_the_clipboard_down_along_a_drag(s: &mut Session) {
    s.quiet();
    let before = s.state();
    tap(s, KeyCode::KeyM);
    let at = s.on_the_terrain();
    s.to(at);
    s.frame();
    s.left(true);
    s.to((at.0 + 6.0, at.1 + 4.0));
    s.frame();
    s.left(false);
    s.quiet();
    s.ctrl(KeyCode::KeyC);
    s.quiet();
    let clip = {
        let doc = s.ed.document();
        let d = doc.read().unwrap();
        d.scene.clipboard.as_ref().map(|c| c.size)
    };
    let size = clip.expect("the box was copied");
    tap(s, KeyCode::KeyJ);
    assert_eq!(s.ed.brush().tool, app::ui::tools::Tool::Stamp);
    tap(s, KeyCode::KeyH);
    assert_eq!(s.ed.brush().stamp_quarters, 1);
    s.to(at);
    s.quiet();
    assert!(
        s.ed.paste_preview_faces() > 0,
        "the stamp shows under the cursor"
    );
    s.left(true);
    for k in 1..=10 {
        s.to((at.0 + 12.0 * f64::from(k), at.1 + 2.0 * f64::from(k)));
        s.frame();
    }
    assert_eq!(s.state().0, before.0, "nothing changes before the release");
    s.left(false);
    s.quiet();
    let (label, command) = s.last_command().expect("a step");
    let Command::Stamp {
        at: places,
        quarters,
    } = command
    else {
        panic!("{label}: not a stamp");
    };
    assert_eq!(quarters, 1);
    assert!(places.len() >= 2, "{label} (a clip of {size})");
    let turned = app::editor::stamp::turned_size(size, 1);
    for w in places.windows(2) {
        assert!(
            (w[1] - w[0]).abs().cmpge(turned).any(),
            "{places:?} overlap"
        );
    }
    assert_ne!(s.state().0, before.0);
    s.ctrl(KeyCode::KeyZ);
    s.quiet();
    assert_eq!(s.state().0, before.0, "undone");
    s.chord(false, true, false, KeyCode::KeyH);
    assert_eq!(s.ed.brush().stamp_quarters, 0, "Shift + H turns back");
    s.ctrl(KeyCode::KeyD);
    tap(s, KeyCode::KeyT);
}

/// P, then "random" and a second material in the Tools panel: a stroke paints the terrain in
/// both (its command says so); "darken" then repaints with the darker neighbours.
pub fn the_colour_modes_are_chosen_in_the_tools_panel(s: &mut Session) {
    s.quiet();
    let before = s.state();
    tap(s, KeyCode::KeyP);
    s.click_on("random", MouseButton::Left);
    let material = s.ed.brush().material;
    let other = if material == 1 { 2 } else { 1 };
    let name = {
        let doc = s.ed.document();
        let d = doc.read().unwrap();
        let m = d.scene.world.materials().get(other).unwrap();
        format!(
            "random among {other}: {}",
            app::ui::swatch::kind_name(m.kind)
        )
    };
    s.click_on(&name, MouseButton::Left);
    match &s.ed.brush().paint {
        PaintMode::Random { among, .. } => assert_eq!(among.len(), 2, "{among:?}"),
        other => panic!("{other:?}"),
    }
    let at = s.on_the_terrain();
    s.to(at);
    s.frame();
    s.left(true);
    s.to((at.0 + 20.0, at.1));
    s.frame();
    s.left(false);
    s.quiet();
    let (label, command) = s.last_command().expect("a step");
    let Command::Stroke(stroke) = command else {
        panic!("{label}: not a stroke");
    };
    assert!(
        matches!(&stroke.paint, PaintMode::Random { among, .. } if among.len() == 2),
        "{:?}",
        stroke.paint
    );
    assert_ne!(s.state().0, before.0);
    s.click_on("darken", MouseButton::Left);
    assert_eq!(s.ed.brush().paint, PaintMode::Darken);
    s.click_on("solid", MouseButton::Left);
    assert_eq!(s.ed.brush().paint, PaintMode::Solid);
    s.ctrl(KeyCode::KeyZ);
    s.quiet();
    assert_eq!(s.state().0, before.0, "undone");
    tap(s, KeyCode::KeyT);
}

fn selected(s: &Session) -> u64 {
    let doc = s.ed.document();
    let d = doc.read().unwrap();
    d.scene.selection.as_ref().map_or(0, |x| x.voxels.count())
}

/// The selection tool's new modes from the Tools panel: "wand: face" takes the clicked face's
/// region; "rectangle" a screen rectangle through all depth; "rectangle: visible" fewer
/// voxels, only those it shows; Shift + Ctrl on a box drag keeps what both hold.
pub fn the_face_wand_and_screen_rectangles_select(s: &mut Session) {
    s.quiet();
    tap(s, KeyCode::KeyM);
    s.click_on("wand: face", MouseButton::Left);
    let at = s.on_the_terrain();
    s.to(at);
    s.frame();
    s.left(true);
    s.left(false);
    s.quiet();
    let (label, _) = s.last_command().expect("a step");
    assert!(label.starts_with("Select the face region at"), "{label}");
    let face = selected(s);
    assert!(face > 0);
    assert!(
        s.ed.selection_tint_faces() >= face as usize,
        "the face region's voxels are tinted"
    );
    let (x0, y0, w, h) = s.ed.view_area();
    let centre = (
        f64::from(x0) + f64::from(w) * 0.5,
        f64::from(y0) + f64::from(h) * 0.5,
    );
    let (p1, p2) = (
        (centre.0 - f64::from(w) / 5.0, centre.1 - f64::from(h) / 6.0),
        (centre.0 + f64::from(w) / 5.0, centre.1 + f64::from(h) / 6.0),
    );
    assert!(!s.ed.on_ui_at(p1.0, p1.1) && !s.ed.on_ui_at(p2.0, p2.1));
    let drag = |s: &mut Session| {
        s.to(p1);
        s.frame();
        s.left(true);
        s.to(((p1.0 + p2.0) * 0.5, (p1.1 + p2.1) * 0.5));
        s.frame();
        s.to(p2);
        s.frame();
        s.left(false);
        s.quiet();
        selected(s)
    };
    s.click_on("rectangle", MouseButton::Left);
    let all = drag(s);
    s.click_on("rectangle: visible", MouseButton::Left);
    let visible = drag(s);
    assert!(
        0 < visible && visible < all,
        "visible {visible}, all depth {all}"
    );
    let (label, _) = s.last_command().expect("a step");
    assert!(label.contains("visible voxels"), "{label}");
    s.ctrl(KeyCode::KeyD);
    s.click_on("box", MouseButton::Left);
    tap(s, KeyCode::KeyT);
}

/// File → Export mesh (Ctrl + Shift + E) without a native dialog: the in-app browser asks,
/// a typed name without an extension becomes a .glb, written on the file thread (a valid
/// GLB header, the length it says), and the status line says how many triangles; File →
/// "one quad per voxel face" makes the next export larger.
pub fn the_scene_exports_as_a_mesh_from_the_browser(s: &mut Session, dir: &std::path::Path) {
    s.chord(true, true, false, KeyCode::KeyE);
    s.quiet();
    assert!(s.ed.browser_open(), "Export mesh asks in the browser");
    s.ctrl(KeyCode::KeyA);
    s.ed.input(app::ui::Input::Text("exported".into()));
    s.key(KeyCode::Enter, true);
    s.key(KeyCode::Enter, false);
    s.quiet();
    s.quiet();
    let file = dir.join("exported.glb");
    let bytes = std::fs::read(&file).expect("the mesh was written");
    assert_eq!(&bytes[..4], b"glTF");
    assert_eq!(
        u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize,
        bytes.len()
    );
    let triangles = |s: &Session| {
        let notice = s.ed.notice().unwrap_or_default().to_string();
        assert!(
            notice.starts_with("Exported ") && notice.contains("triangles"),
            "{notice}"
        );
        notice["Exported ".len()..]
            .split(' ')
            .next()
            .unwrap()
            .parse::<u64>()
            .unwrap()
    };
    let merged = triangles(s);
    // File → one quad per voxel face: the next export has more triangles.
    s.click_on("File", MouseButton::Left);
    s.click_on("one quad per voxel face (watertight)", MouseButton::Left);
    assert!(!s.ed.settings().mesh_export.greedy);
    s.key(KeyCode::Escape, true);
    s.key(KeyCode::Escape, false);
    s.quiet();
    s.chord(true, true, false, KeyCode::KeyE);
    s.quiet();
    s.ctrl(KeyCode::KeyA);
    s.ed.input(app::ui::Input::Text("faces".into()));
    s.key(KeyCode::Enter, true);
    s.key(KeyCode::Enter, false);
    s.quiet();
    s.quiet();
    assert!(dir.join("faces.glb").exists());
    let faces = triangles(s);
    assert!(faces > merged, "{faces} per face, {merged} merged");
}

/// File → New from a heightmap…: the browser asks, the typed PNG becomes a new untitled
/// terrain (a column per pixel, white 256 voxels tall).
pub fn a_heightmap_becomes_a_new_terrain(s: &mut Session, dir: &std::path::Path) {
    let image = dir.join("hm.png");
    {
        let file = std::fs::File::create(&image).unwrap();
        let mut e = png::Encoder::new(std::io::BufWriter::new(file), 9, 5);
        e.set_color(png::ColorType::Grayscale);
        e.set_depth(png::BitDepth::Eight);
        let data: Vec<u8> = (0..45).map(|i| (i * 5) as u8).collect();
        e.write_header().unwrap().write_image_data(&data).unwrap();
    }
    assert!(
        !s.ed.document().read().unwrap().dirty,
        "no question about changes"
    );
    let generation = s.ed.generation();
    s.click_on("File", MouseButton::Left);
    s.click_on("New from a heightmap…", MouseButton::Left);
    assert!(s.ed.browser_open(), "the browser asks for the image");
    s.ed.input(app::ui::Input::Text(image.display().to_string()));
    s.key(KeyCode::Enter, true);
    s.key(KeyCode::Enter, false);
    s.quiet();
    s.settle();
    s.quiet();
    assert!(
        s.ed.generation() > generation,
        "the terrain replaced the document"
    );
    let doc = s.ed.document();
    let d = doc.read().unwrap();
    assert_eq!(d.path, None, "untitled");
    let view = d.scene.world.read();
    assert_eq!(view.dims().voxels(), glam::IVec3::new(16, 256, 8));
    // The brightest pixel (44 · 5 = 220) at (8, 4): round(220 / 255 · 256) voxels.
    let top = (0..256)
        .rev()
        .find(|y| view.voxel(glam::IVec3::new(8, *y, 4)).unwrap().is_some())
        .map(|y| y + 1);
    assert_eq!(top, Some((220.0f64 / 255.0 * 256.0).round() as i32));
}

/// File → Render image…: the window's Render… asks where (the browser), the job renders on
/// its own session while the editor keeps drawing frames, and the picture is written with
/// the window's options (40 × 30, a transparent background).
pub fn a_finished_render_is_written_while_the_editor_runs(s: &mut Session, dir: &std::path::Path) {
    let out = dir.join("shot.png");
    s.click_on("File", MouseButton::Left);
    s.click_on("Render image…", MouseButton::Left);
    s.frame();
    s.click_on("Render…", MouseButton::Left);
    assert!(s.ed.browser_open(), "the browser asks where");
    s.ctrl(KeyCode::KeyA);
    s.ed.input(app::ui::Input::Text("shot.png".into()));
    s.key(KeyCode::Enter, true);
    s.key(KeyCode::Enter, false);
    s.quiet();
    let started = std::time::Instant::now();
    let mut frames = 0;
    while !out.exists() {
        let errors = s.ed.take_errors();
        assert!(errors.is_empty(), "{errors:?}");
        assert!(started.elapsed().as_secs() < 120, "never rendered");
        s.frame();
        frames += 1;
    }
    s.quiet();
    s.frame();
    assert!(frames > 0, "the editor drew frames meanwhile");
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&out).unwrap()));
    let reader = decoder.read_info().unwrap();
    let info = reader.info();
    assert_eq!(
        (info.width, info.height, info.color_type),
        (40, 30, png::ColorType::Rgba)
    );
    assert!(s.ed.take_errors().is_empty());
}
