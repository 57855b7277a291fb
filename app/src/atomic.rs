//! Atomic file replacement: write a temporary file in the target's folder, flush and fsync
//! it, then rename it over the target (and fsync the folder). A failure at any step leaves
//! the previous file as it was and removes the temporary file. A process killed mid-save
//! leaves the previous file whole and its temporary file behind; the next save of the same
//! file removes such leftovers of processes no longer running.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// Replaces `path` with what `write` produces, atomically.
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> io::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "the path names no file"))?;
    let tmp = dir.join(format!(
        ".{}.tmp-{}-{}",
        name.to_string_lossy(),
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let result = (|| {
        let file = OpenOptions::new().write(true).create_new(true).open(&tmp)?;
        let mut out = BufWriter::new(file);
        write(&mut out)?;
        let file = out.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        drop(file);
        fs::rename(&tmp, path)?;
        // Make the rename itself durable; not every platform can open a folder.
        if let Ok(d) = File::open(&dir) {
            let _ = d.sync_all();
        }
        Ok(())
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    } else {
        remove_stale(&dir, &name.to_string_lossy());
    }
    result
}

/// Removes temporary files of `name` in `dir` left by processes that no longer run (killed
/// mid-save). Only where `/proc` tells which processes run (Linux); errors are ignored.
fn remove_stale(dir: &Path, name: &str) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let prefix = format!(".{name}.tmp-");
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let file = entry.file_name();
        let Some(rest) = file.to_str().and_then(|f| f.strip_prefix(&prefix)) else {
            continue;
        };
        let Some(pid) = rest.split('-').next().and_then(|p| p.parse::<u32>().ok()) else {
            continue;
        };
        if pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists() {
            let _ = fs::remove_file(entry.path());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> crate::scratch::Scratch {
        crate::scratch::Scratch::new(&format!("atomic-{name}"))
    }

    #[test]
    fn replaces_and_leaves_no_temporary_file() {
        let d = scratch("ok");
        let p = d.join("scene.ron");
        fs::write(&p, b"old").unwrap();
        write_atomic(&p, |w: &mut dyn Write| w.write_all(b"new")).unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"new");
        assert_eq!(fs::read_dir(&d).unwrap().count(), 1);
    }

    #[test]
    fn failure_midway_keeps_the_previous_file() {
        let d = scratch("fail");
        let p = d.join("scene.ron");
        fs::write(&p, b"precious").unwrap();
        let err = write_atomic(&p, |w: &mut dyn Write| {
            w.write_all(&[7; 100_000])?;
            Err(io::Error::other("disk full (simulated)"))
        })
        .unwrap_err();
        assert!(err.to_string().contains("disk full"));
        assert_eq!(fs::read(&p).unwrap(), b"precious");
        assert_eq!(
            fs::read_dir(&d).unwrap().count(),
            1,
            "temporary file removed"
        );
    }

    #[test]
    fn leftovers_of_killed_saves_are_removed_by_the_next_save() {
        let d = scratch("stale");
        let p = d.join("scene.ron");
        // A process id that is not running (beyond the kernel's pid_max of 2^22) and this
        // process's own in-flight name, which must stay.
        let dead = d.join(".scene.ron.tmp-4999999-0");
        let other = d.join(".other.ron.tmp-4999999-0");
        fs::write(&dead, b"torn").unwrap();
        fs::write(&other, b"another file's").unwrap();
        write_atomic(&p, |w: &mut dyn Write| w.write_all(b"new")).unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"new");
        assert!(!dead.exists(), "the dead process's temporary file is gone");
        assert!(
            other.exists(),
            "another file's temporary file is not touched"
        );
    }

    #[test]
    fn missing_folder_is_an_error() {
        let d = scratch("missing");
        let p = d.join("no/such/folder/scene.ron");
        assert!(write_atomic(&p, |w: &mut dyn Write| w.write_all(b"x")).is_err());
    }

    #[test]
    fn real_full_device_reports_and_keeps_nothing() {
        // /dev/full answers every write with ENOSPC, but it is not a folder we can put a
        // temporary file in; what matters is the error, not a panic.
        let p = Path::new("/dev/full/scene.ron");
        assert!(write_atomic(p, |w: &mut dyn Write| w.write_all(b"x")).is_err());
    }
}
