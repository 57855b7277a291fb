//! Saves survive being killed: a process writing a large project (6 MB) over an existing one
//! is killed with SIGKILL at random moments of its write, from when its temporary file appears
//! to a little past its usual end (50 kills at least, on until 25 landed inside a write);
//! after every kill the file on disk is byte for byte
//! either the old project or the complete new one, never a torn mix, and the next complete
//! save removes what the killed ones left behind. Every save of the editor and the command
//! line goes through the same atomic write (`app::atomic`) as `voxbrick new` here.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Instant;

fn new_project(seed: &str, out: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_voxbrick"));
    c.args([
        "new",
        "--terrain",
        "--size",
        "768x128x768",
        "--workers",
        "2",
        "--seed",
        seed,
    ])
    .arg(out)
    .stdout(Stdio::null())
    .stderr(Stdio::null());
    c
}

#[test]
fn saves_killed_at_random_moments_leave_the_old_file_or_the_complete_new_one() {
    let dir = app::scratch::Scratch::new("kills");
    // The two complete contents.
    let (a, b) = (dir.join("a.ron"), dir.join("b.ron"));
    assert!(new_project("1", &a).status().unwrap().success());
    assert!(new_project("2", &b).status().unwrap().success());
    let (bytes_a, bytes_b) = (std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    assert_ne!(bytes_a, bytes_b);
    assert!(
        bytes_a.len() > 4 << 20,
        "a large project: {} bytes",
        bytes_a.len()
    );
    let target = dir.join("scene.ron");
    std::fs::copy(&a, &target).unwrap();
    let leftovers = || {
        std::fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .filter(|e| {
                e.file_name()
                    .to_string_lossy()
                    .starts_with(".scene.ron.tmp-")
            })
            .count()
    };
    // When the write starts (its temporary file appears) and when the process is done: the
    // kills fall around that window, so most land inside a write.
    let started = Instant::now();
    let mut child = new_project("2", &target).spawn().unwrap();
    let mut write_start = None;
    while child.try_wait().unwrap().is_none() {
        if write_start.is_none() && leftovers() > 0 {
            write_start = Some(started.elapsed());
        }
        std::thread::sleep(std::time::Duration::from_micros(500));
    }
    let done = started.elapsed();
    let write_start = write_start.unwrap_or(done / 2);
    let window = done.saturating_sub(write_start);
    eprintln!("a save: its write starts after {write_start:?}, the process ends after {done:?}");
    // A fixed-seed generator: the same kill moments every run.
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut mid_write, mut completed) = (0, 0);
    // At least 50 kills, and on until 25 of them landed inside a write (a loaded machine
    // stretches the start-up more than the write: the delay shrinks after a kill that came too
    // late), 150 at the most.
    let mut scale = 1.2;
    let mut kills = 0;
    while (kills < 50 || mid_write < 25) && kills < 150 {
        let kill = kills;
        kills += 1;
        let seed = if kill % 2 == 0 { "1" } else { "2" };
        let was = leftovers();
        let mut child = new_project(seed, &target).spawn().unwrap();
        // The write has begun when its temporary file appears; the kill comes a random moment
        // into it (up to 1.2 times its usual length: some land after the rename).
        while leftovers() <= was && child.try_wait().unwrap().is_none() {
            std::thread::sleep(std::time::Duration::from_micros(200));
        }
        let delay = window.mul_f64(scale * uniform());
        std::thread::sleep(delay);
        let finished = matches!(child.try_wait(), Ok(Some(_)));
        let _ = child.kill(); // SIGKILL
        let _ = child.wait();
        let now = std::fs::read(&target).unwrap();
        assert!(
            now == bytes_a || now == bytes_b,
            "kill {kill} {delay:?} into the write: the file is neither the old nor the new project ({} bytes)",
            now.len()
        );
        if finished {
            completed += 1;
            scale = (scale * 0.8).max(0.05);
        } else if leftovers() > was {
            // Killed between the temporary file's creation and the rename.
            mid_write += 1;
        }
    }
    eprintln!("{mid_write} kills during a write, {completed} saves completed, of {kills}");
    assert!(
        mid_write >= 25,
        "only {mid_write} of {kills} kills landed inside a write: the test proves too little"
    );
    // The next complete save replaces the file and removes the dead processes' leftovers.
    assert!(new_project("1", &target).status().unwrap().success());
    assert_eq!(std::fs::read(&target).unwrap(), bytes_a);
    assert_eq!(leftovers(), 0, "temporary files of killed saves remain");
    app::formats::load(&target, 1).expect("the file loads");
}
