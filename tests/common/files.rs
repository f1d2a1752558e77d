//! Temporary folders and the project's real test data, for tests that read and write files.

use std::path::{Path, PathBuf};

/// A fresh directory under the system temp dir, unique to a test and this process, removed when
/// dropped.
pub struct TempDir(PathBuf);

impl TempDir {
    /// A fresh `kelvin-<prefix>-<pid>-<test>` folder.
    pub fn new(prefix: &str, test: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("kelvin-{prefix}-{}-{test}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("create temp dir");
        TempDir(dir)
    }
    pub fn join(&self, name: impl AsRef<Path>) -> PathBuf {
        self.0.join(name)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// `../shared/data/<sub>` if it is there; otherwise None, after saying that the test skips.
pub fn shared_data(sub: &str) -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data").join(sub);
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!("skipping: {} not found (real test data absent)", dir.display());
        None
    }
}
