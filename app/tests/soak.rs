//! The soak test's short form (CI): a seeded random session of more than 10 000 inputs through
//! the editor's edit thread, with viewport frames on the machine's Vulkan device (lavapipe in
//! CI) and the validation layer, stays clean; and a failure reports the seed and the shortest
//! failing prefix as a replay script that `voxbrick replay` runs headlessly. Without a Vulkan
//! driver the GPU half skips, saying so, unless VOXBRICK_REQUIRE_GPU=1 makes that a failure.

mod window;

use app::soak::{SoakOptions, soak};

#[test]
fn a_short_soak_with_viewport_frames_is_clean() {
    let opts = SoakOptions {
        seed: 26,
        events: 2000,
        check_every: 500,
        out_dir: window::scratch("soak-short"),
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
        Err(f)
            if f.event == 0
                && f.message.contains("Vulkan")
                && std::env::var("VOXBRICK_REQUIRE_GPU").as_deref() != Ok("1") =>
        {
            eprintln!(
                "SKIPPED: no Vulkan device ({f}); VOXBRICK_REQUIRE_GPU=1 makes this a failure"
            );
        }
        Err(f) => panic!("{f}"),
    }
}

#[test]
fn a_failure_names_the_seed_and_its_shortest_failing_prefix_as_a_replay_script() {
    let dir = window::scratch("soak-failing");
    let opts = SoakOptions {
        seed: 7,
        events: 400,
        check_every: 100,
        device: None,
        fail_at: Some(137),
        out_dir: dir.clone(),
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
