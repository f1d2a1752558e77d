//! What made an output: the program, the inputs (content hashes of the files a job read) and the
//! settings, so that pieces of one job made on different machines are checked to come from the
//! same build and inputs before they are joined, and a finished output is known to be the job's.
//! EXRs carry it as one text attribute, `kelvin`, a JSON object; bake parts in their header.

use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use sha2::{Digest, Sha256};

/// The name of the EXR header attribute that holds the provenance.
pub const ATTRIBUTE: &str = "kelvin";

/// `sha256:` and the lowercase hex SHA-256 of a digest's state.
fn hex(hasher: Sha256) -> String {
    let hex: String = hasher.finalize().iter().map(|b| format!("{b:02x}")).collect();
    format!("sha256:{hex}")
}

/// `sha256:` and the lowercase hex SHA-256 of `bytes`.
pub fn sha256(bytes: &[u8]) -> String {
    hex(Sha256::new_with_prefix(bytes))
}

/// A file a loader read: its path and the SHA-256 of the very bytes it parsed (hashed in memory
/// when read, so a file replaced afterwards is not mistaken for the one the output shows).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InputFile {
    /// The path it was read from.
    pub path: PathBuf,
    /// `sha256:` and the hex digest of its bytes.
    pub sha256: String,
}

impl InputFile {
    /// The record of `bytes`, read from `path`.
    pub fn read(path: &Path, bytes: &[u8]) -> Self {
        Self { path: path.to_path_buf(), sha256: sha256(bytes) }
    }

    /// The record of a file whose bytes went through `hasher` ([`Sha256`] state) as they were read.
    pub fn hashed(path: &Path, hasher: Sha256) -> Self {
        Self { path: path.to_path_buf(), sha256: hex(hasher) }
    }
}

/// Every file a job read: the scene file, the environment map, and what the scene references
/// (buffers, images, IES profiles).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Inputs {
    /// The scene file (None: the embedded default scene).
    pub scene: Option<InputFile>,
    /// The environment map.
    pub env: Option<InputFile>,
    /// The files the scene references, in the order read.
    pub referenced: Vec<InputFile>,
}

/// The prefix of a provenance key naming a file the scene references: `input ` and its path
/// relative to the scene's folder (paths differ between machines; the layout beside the scene does
/// not), so that a done-check can hash the same files again.
pub const INPUT_PREFIX: &str = "input ";

impl Inputs {
    /// Provenance entries: `scene`, `env` and one `input <path>` per referenced file (relative to
    /// the scene's folder when under it; a file read twice keeps its last digest).
    pub fn entries(&self) -> BTreeMap<String, String> {
        let mut entries = BTreeMap::new();
        if let Some(scene) = &self.scene {
            entries.insert("scene".to_owned(), scene.sha256.clone());
        }
        if let Some(env) = &self.env {
            entries.insert("env".to_owned(), env.sha256.clone());
        }
        let base = self.scene.as_ref().and_then(|s| s.path.parent());
        for f in &self.referenced {
            let rel = base.and_then(|b| f.path.strip_prefix(b).ok()).unwrap_or(&f.path);
            entries.insert(format!("{INPUT_PREFIX}{}", rel.display()), f.sha256.clone());
        }
        entries
    }
}

/// `sha256:` and the lowercase hex SHA-256 of the file at `path` (what `sha256sum` prints).
pub fn file_sha256(path: &Path) -> std::io::Result<String> {
    let mut file = std::fs::File::open(path)?;
    let mut hasher = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        match file.read(&mut buf)? {
            0 => break,
            n => hasher.update(&buf[..n]),
        }
    }
    Ok(hex(hasher))
}

/// The running program: its file name and SHA-256 (two builds of one commit with another
/// compiler, target CPU or libm differ here), hashed once per process.
pub fn program() -> &'static str {
    static PROGRAM: OnceLock<String> = OnceLock::new();
    PROGRAM.get_or_init(|| {
        let exe = std::env::current_exe();
        let name = exe.as_ref().ok().and_then(|p| p.file_name()).map(|n| n.to_string_lossy().into_owned());
        let hash = exe.as_ref().ok().and_then(|p| file_sha256(p).ok());
        format!("{} {}", name.unwrap_or_else(|| "unknown".into()), hash.unwrap_or_else(|| "unhashed".into()))
    })
}

/// Named text entries: what made a file.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Provenance(pub BTreeMap<String, String>);

impl Provenance {
    /// kelvin's version and the program ([`program`]): what every EXR kelvin writes records.
    pub fn of_program() -> Self {
        Self::default().with("version", env!("CARGO_PKG_VERSION")).with("program", program())
    }

    /// This with `key` set to `value`.
    pub fn with(mut self, key: &str, value: impl Into<String>) -> Self {
        self.0.insert(key.to_owned(), value.into());
        self
    }

    /// This with every entry of `entries`.
    pub fn with_all(mut self, entries: BTreeMap<String, String>) -> Self {
        self.0.extend(entries);
        self
    }

    /// This without `key`.
    pub fn without(mut self, key: &str) -> Self {
        self.0.remove(key);
        self
    }

    /// The first key (but those in `ignore`) whose value differs between `self` and `other` (one
    /// may lack it), with both values: None when they agree.
    pub fn difference(&self, other: &Provenance, ignore: &[&str]) -> Option<(String, String, String)> {
        let none = String::from("(none)");
        let keys = self.0.keys().chain(other.0.keys().filter(|k| !self.0.contains_key(*k)));
        keys.filter(|k| !ignore.contains(&k.as_str())).find_map(|k| {
            let (a, b) = (self.0.get(k).unwrap_or(&none), other.0.get(k).unwrap_or(&none));
            (a != b).then(|| (k.clone(), a.clone(), b.clone()))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The digest of "abc" from FIPS 180-2's example.
    #[test]
    fn sha256_of_a_known_file() {
        let path = std::env::temp_dir().join(format!("kelvin-sha-{}", std::process::id()));
        std::fs::write(&path, b"abc").unwrap();
        let digest = file_sha256(&path).unwrap();
        std::fs::remove_file(&path).ok();
        assert_eq!(digest, "sha256:ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
    }

    #[test]
    fn differences_name_the_key() {
        let a = Provenance::default().with("scene", "x").with("tile", "0,0,4,4");
        let b = Provenance::default().with("scene", "y").with("tile", "4,0,8,4");
        assert_eq!(a.difference(&b, &["tile"]), Some(("scene".into(), "x".into(), "y".into())));
        assert_eq!(a.difference(&a.clone().with("tile", "1"), &["tile"]), None);
        let c = a.clone().without("scene");
        assert_eq!(a.difference(&c, &["tile"]), Some(("scene".into(), "x".into(), "(none)".into())));
    }
}
