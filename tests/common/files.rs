//! Temporary folders and the repository's real test data, for tests that read and write files.

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

/// `tests/data/<rel>`, the repository's real test data (origins and licenses in
/// `tests/data/SOURCES.md`). Panics, naming the path, when it is absent: a test that needs real
/// data fails rather than passing without it.
pub fn test_data(rel: &str) -> PathBuf {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(rel);
    assert!(path.exists(), "real test data missing: {} (see tests/data/SOURCES.md)", path.display());
    path
}
