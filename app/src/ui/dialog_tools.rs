//! The native dialogs besides the portal: zenity (GTK) and kdialog (KDE), run as programs
//! where one is installed. Many Linux desktops have one of them and no xdg-desktop-portal.

use super::purpose::Purpose;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// A dialog from the first of zenity and kdialog that runs: Some(the path, or None when the
/// user cancelled); None when neither could be shown (not installed, no display).
pub fn pick(
    purpose: Purpose,
    folder: Option<&Path>,
    name: Option<&str>,
) -> Option<Option<PathBuf>> {
    let start = start_path(folder, name);
    [zenity_args(purpose, &start), kdialog_args(purpose, &start)]
        .into_iter()
        .find_map(|(program, args)| run(program, &args))
}

/// Where the dialog starts: the folder, and the file name in it.
fn start_path(folder: Option<&Path>, name: Option<&str>) -> String {
    let folder = folder.map(Path::to_path_buf).unwrap_or_default();
    let mut s = folder.display().to_string();
    if !s.is_empty() && !s.ends_with('/') {
        s.push('/');
    }
    s + name.unwrap_or_default()
}

/// zenity's arguments for a purpose.
pub fn zenity_args(purpose: Purpose, start: &str) -> (&'static str, Vec<String>) {
    let (what, exts) = purpose.filter();
    let patterns: Vec<String> = exts.iter().map(|e| format!("*.{e}")).collect();
    let mut args = vec![
        "--file-selection".to_string(),
        format!("--file-filter={what} | {}", patterns.join(" ")),
    ];
    if purpose.saves() {
        args.extend(["--save".into(), "--confirm-overwrite".into()]);
    }
    if !start.is_empty() {
        args.push(format!("--filename={start}"));
    }
    ("zenity", args)
}

/// kdialog's arguments for a purpose.
pub fn kdialog_args(purpose: Purpose, start: &str) -> (&'static str, Vec<String>) {
    let (what, exts) = purpose.filter();
    let patterns: Vec<String> = exts.iter().map(|e| format!("*.{e}")).collect();
    let verb = if purpose.saves() {
        "--getsavefilename"
    } else {
        "--getopenfilename"
    };
    let start = if start.is_empty() { "." } else { start };
    (
        "kdialog",
        vec![
            verb.into(),
            start.into(),
            format!("{} ({what})", patterns.join(" ")),
        ],
    )
}

/// Runs a dialog program: exit 0 with a path, exit 1 a cancel (both programs' rule); None
/// when it could not run or failed otherwise.
fn run(program: &str, args: &[String]) -> Option<Option<PathBuf>> {
    let out = Command::new(program)
        .args(args)
        .stdin(Stdio::null())
        .stderr(Stdio::null())
        .output()
        .ok()?;
    match out.status.code() {
        Some(0) => {
            let text = String::from_utf8_lossy(&out.stdout);
            let path = text.trim_end_matches(['\n', '\r']);
            Some((!path.is_empty()).then(|| PathBuf::from(path)))
        }
        Some(1) => Some(None),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zenity_and_kdialog_get_the_purposes_filter_and_mode() {
        let start = start_path(Some(Path::new("/work/scenes")), Some("scene.ron"));
        assert_eq!(start, "/work/scenes/scene.ron");
        let (_, z) = zenity_args(Purpose::SaveAs, &start);
        assert_eq!(
            z,
            [
                "--file-selection",
                "--file-filter=voxbrick project | *.ron",
                "--save",
                "--confirm-overwrite",
                "--filename=/work/scenes/scene.ron"
            ]
        );
        let (_, z) = zenity_args(Purpose::Open, "");
        assert_eq!(
            z,
            [
                "--file-selection",
                "--file-filter=Scenes | *.ron *.vox *.qb *.schem"
            ]
        );
        let (_, k) = kdialog_args(Purpose::Import, "/m/");
        assert_eq!(k, ["--getopenfilename", "/m/", "*.vox (MagicaVoxel)"]);
    }

    #[test]
    fn a_program_that_is_not_there_is_no_dialog() {
        assert_eq!(run("voxbrick-no-such-dialog-program", &[]), None);
        // exit 1 is a cancel; exit 0 a path (sh stands in for the dialog).
        let sh = |script: &str| run("sh", &["-c".to_string(), script.to_string()]);
        assert_eq!(sh("exit 1"), Some(None));
        assert_eq!(sh("echo /a/b.ron"), Some(Some(PathBuf::from("/a/b.ron"))));
        assert_eq!(sh("exit 5"), None);
    }
}
