//! The `voxbrick` binary end to end: the main job's statistics, and clear errors.

use std::process::Command;

fn voxbrick(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_voxbrick"))
        .args(args)
        .output()
        .expect("voxbrick runs")
}

fn field<'a>(out: &'a str, name: &str) -> &'a str {
    out.lines()
        .find(|l| l.starts_with(name))
        .unwrap_or_else(|| panic!("no {name} in:\n{out}"))
}

#[test]
fn stats_reports_the_default_scene() {
    let out = voxbrick(&["stats", "--size", "small", "--workers", "2"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(field(&text, "scene").contains("128 x 64 x 128 voxels"));
    let solid: u64 = field(&text, "solid")
        .split_whitespace()
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    assert!(
        solid > 128 * 128 * 16,
        "terrain is solid underground: {solid}"
    );
    assert!(field(&text, "materials").contains("7 in the table"));
    assert!(field(&text, "pick").contains("normal [0, 1, 0]"), "{text}");
    // The same scene with another worker count has the same content.
    let other = voxbrick(&["stats", "--size", "small", "--workers", "1"]);
    let other = String::from_utf8(other.stdout).unwrap();
    assert_eq!(field(&text, "content hash"), field(&other, "content hash"));
}

#[test]
fn bad_arguments_are_one_clear_error() {
    let out = voxbrick(&["stats", "--size", "huge"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("invalid value 'huge'"), "{err}");
    let out = voxbrick(&["stats", "--workers", "5000"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.starts_with("voxbrick: ") && err.contains("5000 workers"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
}
