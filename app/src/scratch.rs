//! Tests' scratch folders: a fresh folder under the system's temporary folder, removed when
//! the test that made it ends — kept when it fails (the files are the evidence). Tests only:
//! the `test-hooks` feature, which only the tests enable.

use std::path::{Path, PathBuf};

/// A scratch folder, created empty, removed on drop unless the thread is panicking.
#[derive(Debug)]
pub struct Scratch(PathBuf);

impl Scratch {
    /// `voxbrick-<pid>-<name>` under the temporary folder, emptied and created.
    pub fn new(name: &str) -> Self {
        let d = std::env::temp_dir().join(format!("voxbrick-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).expect("creating a scratch folder");
        Self(d)
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scratch_folder_is_gone_after_its_test() {
        let kept;
        {
            let s = Scratch::new("scratch-self-test");
            std::fs::write(s.join("f"), b"x").unwrap();
            assert!(s.join("f").is_file());
            kept = s.path().to_path_buf();
        }
        assert!(!kept.exists());
    }
}
