//! The soak test's short form (CI): seeded random sessions of more than 10 000 inputs each —
//! window input events into a headless editor (egui, the key map, picking, the tools; its
//! frames drawn offscreen), and edits into the edit thread with a bare viewport's frames — on
//! the machine's Vulkan device (lavapipe in CI) with the validation layer, stay clean; and a
//! failure reports the seed and the shortest failing prefix as a replay script that `voxbrick
//! replay` runs headlessly. Without a Vulkan driver the GPU tests skip, saying so, unless
//! VOXBRICK_REQUIRE_GPU=1 makes that a failure.

mod window;

use app::soak::{SoakFailure, SoakOptions, Through, soak};

/// A failure to find a Vulkan device skips (saying so) where VOXBRICK_REQUIRE_GPU is not 1.
fn no_device(f: &SoakFailure) -> bool {
    let skip = f.event == 0
        && f.message.contains("Vulkan")
        && std::env::var("VOXBRICK_REQUIRE_GPU").as_deref() != Ok("1");
    if skip {
        eprintln!("SKIPPED: no Vulkan device ({f}); VOXBRICK_REQUIRE_GPU=1 makes this a failure");
    }
    skip
}

#[test]
fn a_short_soak_through_the_editors_window_handlers_is_clean() {
    let out = window::scratch("soak-editor");
    let opts = SoakOptions {
        seed: 32,
        through: Through::Editor,
        events: 1200,
        check_every: 400,
        size: glam::UVec3::new(48, 24, 48),
        window: (320, 200),
        frame_every: 6,
        out_dir: out.to_path_buf(),
        ..SoakOptions::default()
    };
    match soak(&opts) {
        Ok(r) => {
            eprintln!(
                "{} events, {} inputs, {} frames, {} checks in {:?}: {:?}",
                r.events, r.inputs, r.frames, r.checks, r.elapsed, r.kinds
            );
            assert!(r.inputs >= 10_000, "{} inputs", r.inputs);
            assert_eq!(r.checks, 4, "every 400 events and at the end");
            for kind in [
                "stroke",
                "select",
                "selection operation",
                "paste",
                "undo / redo burst",
                "resize",
                "save and reopen",
                "panel click or drag",
                "document replaced",
            ] {
                assert!(r.kinds.get(kind).copied().unwrap_or(0) > 0, "no {kind}");
            }
        }
        Err(f) if no_device(&f) => {}
        Err(f) => panic!("{f}"),
    }
}

#[test]
fn a_short_soak_through_the_edit_thread_with_viewport_frames_is_clean() {
    let out = window::scratch("soak-short");
    let opts = SoakOptions {
        seed: 26,
        through: Through::Edits,
        events: 2000,
        check_every: 500,
        out_dir: out.to_path_buf(),
        ..SoakOptions::default()
    };
    match soak(&opts) {
        Ok(r) => {
            eprintln!(
                "{} events, {} inputs, {} frames, {} checks in {:?}",
                r.events, r.inputs, r.frames, r.checks, r.elapsed
            );
            assert!(r.inputs >= 10_000, "{} inputs", r.inputs);
            assert_eq!(r.checks, 5, "every 500 events and at the end");
            assert!(r.frames >= 200, "{} frames", r.frames);
            for kind in [
                "stroke end",
                "undo",
                "redo",
                "select",
                "clipboard",
                "palette and materials",
                "terrain",
                "save and reopen",
                "resize",
            ] {
                assert!(r.kinds.get(kind).copied().unwrap_or(0) > 0, "no {kind}");
            }
        }
        Err(f) if no_device(&f) => {}
        Err(f) => panic!("{f}"),
    }
}

#[test]
fn a_failure_names_the_seed_and_its_shortest_failing_prefix_as_a_replay_script() {
    let dir = window::scratch("soak-failing");
    let opts = SoakOptions {
        seed: 7,
        through: Through::Edits,
        events: 400,
        check_every: 100,
        device: None,
        fail_at: Some(137),
        out_dir: dir.to_path_buf(),
        ..SoakOptions::default()
    };
    let f = soak(&opts).expect_err("event 137 fails on purpose");
    assert_eq!((f.seed, f.event, f.shortest), (7, 137, 137), "{f}");
    let text = f.to_string();
    assert!(text.contains("seed 7") && text.contains("137"), "{text}");
    let script = f.script.expect("the shortest failing session is written");
    assert!(script.starts_with(&dir));
    // The prefix replays headlessly.
    window::replay(
        env!("CARGO_BIN_EXE_voxbrick"),
        &script,
        &dir.join("replayed"),
    );
}
