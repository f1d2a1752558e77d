//! What made an output: content hashes of the files a job read, so that pieces of one job made on
//! different machines can be checked to come from the same inputs before they are joined.

use std::io::Read;
use std::path::Path;

use sha2::{Digest, Sha256};

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
    let hex: String = hasher.finalize().iter().map(|b| format!("{b:02x}")).collect();
    Ok(format!("sha256:{hex}"))
}

#[cfg(test)]
mod tests {
    /// The digest of "abc" from FIPS 180-2's example.
    #[test]
    fn sha256_of_a_known_file() {
        let path = std::env::temp_dir().join(format!("kelvin-sha-{}", std::process::id()));
        std::fs::write(&path, b"abc").unwrap();
        let digest = super::file_sha256(&path).unwrap();
        std::fs::remove_file(&path).ok();
        assert_eq!(digest, "sha256:ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
    }
}
