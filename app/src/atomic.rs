//! Atomic file replacement: write a temporary file in the target's folder, flush and fsync
//! it, then rename it over the target (and fsync the folder). A failure at any step leaves
//! the previous file as it was and removes the temporary file.

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
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("voxbrick-atomic-{}-{name}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
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
