//! The file containers: `.glb` chunks, the JSON text, URIs (`data:` and relative paths) and buffers.

use std::path::{Path, PathBuf};

use base64::Engine;
use serde_json::Value;
use sha2::{Digest, Sha256};

use super::{GltfError, MAX_BUFFER_BYTES, Warnings};
use crate::provenance::InputFile;

/// GLB header magic, "glTF" (glTF 2.0 spec, section 4.4 "Binary glTF Layout").
const GLB_MAGIC: &[u8; 4] = b"glTF";
const GLB_HEADER_BYTES: usize = 12;
const CHUNK_HEADER_BYTES: usize = 8;
/// Chunk types "JSON" and "BIN\0" as little-endian u32.
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// The JSON text and, for a `.glb`, its binary chunk.
pub(super) struct Container<'a> {
    pub json: &'a [u8],
    pub bin: Option<&'a [u8]>,
}

/// Reads a whole file, refusing ones over [`MAX_BUFFER_BYTES`].
pub(super) fn read_file(path: &Path, what: &str) -> Result<Vec<u8>, GltfError> {
    let io_error = |e: std::io::Error| match e.kind() {
        std::io::ErrorKind::NotFound => GltfError::NotFound { what: what.into() },
        _ => GltfError::Io { what: what.into(), msg: e.to_string() },
    };
    let len = std::fs::metadata(path).map_err(io_error)?.len();
    if len > MAX_BUFFER_BYTES {
        return Err(GltfError::TooLarge {
            what: what.into(),
            msg: format!("{len} bytes (at most {MAX_BUFFER_BYTES})"),
        });
    }
    std::fs::read(path).map_err(io_error)
}

/// Splits a `.glb` into its JSON and BIN chunks; anything else is taken as JSON text.
pub(super) fn split<'a>(bytes: &'a [u8], what: &str, warnings: &mut Warnings) -> Result<Container<'a>, GltfError> {
    if !bytes.starts_with(GLB_MAGIC) {
        return Ok(Container { json: bytes, bin: None });
    }
    let glb_error = |msg: String| GltfError::Glb { what: what.into(), msg };
    let u32_at = |at: usize| -> Option<u32> { Some(u32::from_le_bytes(bytes.get(at..at + 4)?.try_into().ok()?)) };
    let (Some(version), Some(length)) = (u32_at(4), u32_at(8)) else {
        return Err(glb_error(format!("{} bytes, shorter than the {GLB_HEADER_BYTES}-byte header", bytes.len())));
    };
    if version != 2 {
        return Err(glb_error(format!("container version {version} (only 2 is supported)")));
    }
    let length = length as usize;
    if length > bytes.len() {
        return Err(glb_error(format!("the header declares {length} bytes but the file has {}", bytes.len())));
    }
    if length < bytes.len() {
        warnings.push("", format!("{} bytes after the declared .glb length {length} ignored", bytes.len() - length));
    }
    let mut offset = GLB_HEADER_BYTES;
    let mut chunks: Vec<(u32, &[u8])> = Vec::new();
    while offset < length {
        let (Some(chunk_len), Some(chunk_type)) = (u32_at(offset), u32_at(offset + 4)) else {
            return Err(glb_error(format!("chunk header at byte {offset} cut off at {length}")));
        };
        let start = offset + CHUNK_HEADER_BYTES;
        let end = start.checked_add(chunk_len as usize).filter(|&end| end <= length).ok_or_else(|| {
            glb_error(format!(
                "chunk {} of {chunk_len} bytes at byte {offset} runs past the end ({length})",
                chunks.len()
            ))
        })?;
        chunks.push((chunk_type, &bytes[start..end]));
        // Chunks are 4-byte aligned; a missing pad at the very end is harmless.
        offset = end.next_multiple_of(4);
    }
    let json = match chunks.first() {
        Some(&(CHUNK_JSON, data)) => data,
        Some(&(other, _)) => return Err(glb_error(format!("first chunk has type {other:#010x}, not JSON"))),
        None => return Err(glb_error("no JSON chunk".into())),
    };
    let bin = chunks.get(1).filter(|(t, _)| *t == CHUNK_BIN).map(|&(_, data)| data);
    Ok(Container { json, bin })
}

/// Parses the JSON text; syntax errors carry line and column.
pub(super) fn parse_json(text: &[u8], what: &str) -> Result<Value, GltfError> {
    let text = text.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(text);
    let value: Value = serde_json::from_slice(text).map_err(|e| GltfError::JsonSyntax {
        what: what.into(),
        line: e.line(),
        column: e.column(),
        msg: e.to_string(),
    })?;
    if !value.is_object() {
        return Err(GltfError::Schema { what: what.into(), msg: "the top-level JSON value is not an object".into() });
    }
    Ok(value)
}

/// What a URI points to.
pub(super) enum UriTarget {
    /// Decoded `data:` URI content with its media type.
    Data { bytes: Vec<u8>, mime: String },
    /// A file path, resolved against the base directory (not checked for existence).
    File(PathBuf),
}

/// Resolves a glTF URI: `data:` URIs are decoded, relative references (percent-decoded) are joined to
/// `base_dir`. Remote URIs (`http:` etc.) are refused. The error says why, without the file name.
pub(super) fn resolve_uri(uri: &str, base_dir: Option<&Path>) -> Result<UriTarget, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (header, payload) = rest.split_once(',').ok_or("data: URI without a comma")?;
        let (mime, is_base64) = match header.strip_suffix(";base64") {
            Some(mime) => (mime, true),
            None => (header, false),
        };
        let bytes = if is_base64 {
            let cleaned: Vec<u8> = payload.bytes().filter(|b| !b.is_ascii_whitespace()).collect();
            let engine = base64::engine::GeneralPurpose::new(
                &base64::alphabet::STANDARD,
                base64::engine::GeneralPurposeConfig::new()
                    .with_decode_padding_mode(base64::engine::DecodePaddingMode::Indifferent),
            );
            engine.decode(cleaned).map_err(|e| format!("bad base64 in data: URI: {e}"))?
        } else {
            percent_decode(payload)
        };
        let mime = mime.split(';').next().unwrap_or("").to_ascii_lowercase();
        return Ok(UriTarget::Data { bytes, mime });
    }
    if has_scheme(uri) {
        return Err(format!("URI {uri:?} is not a relative path or data: URI (remote files are not fetched)"));
    }
    let Some(base_dir) = base_dir else {
        return Err(format!("relative URI {uri:?} but no base directory (loaded from memory)"));
    };
    let relative = String::from_utf8_lossy(&percent_decode(uri)).into_owned();
    Ok(UriTarget::File(base_dir.join(relative)))
}

/// RFC 3986 scheme: a letter then letters, digits, '+', '-' or '.', then ':'. One letter is taken as a Windows
/// drive ("C:"), not a scheme.
fn has_scheme(uri: &str) -> bool {
    let Some((scheme, _)) = uri.split_once(':') else { return false };
    scheme.len() > 1
        && scheme.starts_with(|c: char| c.is_ascii_alphabetic())
        && scheme.chars().all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
}

/// Decodes %XX escapes; malformed escapes are kept as they are.
fn percent_decode(text: &str) -> Vec<u8> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = bytes.get(i + 1..i + 3).and_then(|h| std::str::from_utf8(h).ok());
        match (bytes[i], hex.and_then(|h| u8::from_str_radix(h, 16).ok())) {
            (b'%', Some(byte)) => {
                out.push(byte);
                i += 3;
            }
            (b, _) => {
                out.push(b);
                i += 1;
            }
        }
    }
    out
}

/// Loads every buffer: the GLB BIN chunk, `data:` URIs and external files. Each comes back exactly `byteLength`
/// bytes long; a missing source or one shorter than declared is an error.
pub(super) fn load_buffers(
    root: &::gltf::json::Root,
    json: &Value,
    bin: Option<&[u8]>,
    base_dir: Option<&Path>,
    what: &str,
    inputs: &mut Vec<InputFile>,
) -> Result<Vec<Vec<u8>>, GltfError> {
    let mut buffers = Vec::with_capacity(root.buffers.len());
    for (index, buffer) in root.buffers.iter().enumerate() {
        let declared = buffer.byte_length.0;
        if declared > MAX_BUFFER_BYTES {
            return Err(GltfError::TooLarge {
                what: what.into(),
                msg: format!("buffer {index} declares {declared} bytes (at most {MAX_BUFFER_BYTES})"),
            });
        }
        let missing = |source_name: &str, msg: String| GltfError::BufferMissing {
            what: what.into(),
            index,
            source_name: source_name.into(),
            msg,
        };
        let (mut data, source_name) = match (&buffer.uri, bin) {
            // The first buffer of a .glb, without a uri, is the BIN chunk (glTF 2.0 spec, section 4.4.3.3).
            (None, Some(bin)) if index == 0 => (bin.to_vec(), "the .glb BIN chunk".to_string()),
            (None, _) => {
                let meshopt = json.pointer(&format!("/buffers/{index}/extensions/EXT_meshopt_compression")).is_some();
                let why = if meshopt {
                    "an EXT_meshopt_compression fallback buffer (meshopt is not supported)"
                } else {
                    "no uri and no .glb BIN chunk"
                };
                return Err(missing("(no uri)", why.into()));
            }
            (Some(uri), _) => match resolve_uri(uri, base_dir) {
                Ok(UriTarget::Data { bytes, .. }) => (bytes, "its data: URI".to_string()),
                Ok(UriTarget::File(path)) => {
                    let name = path.display().to_string();
                    let (data, read) = read_external(&path, declared).map_err(|msg| missing(&name, msg))?;
                    inputs.push(read);
                    (data, name)
                }
                Err(msg) => return Err(missing(&shorten(uri), msg)),
            },
        };
        if (data.len() as u64) < declared {
            return Err(GltfError::BufferTooShort {
                what: what.into(),
                index,
                source_name,
                declared,
                actual: data.len() as u64,
            });
        }
        data.truncate(declared as usize);
        buffers.push(data);
    }
    Ok(buffers)
}

/// Reads an external buffer file, keeping at most `declared` bytes plus a little slack (so a huge wrong file is
/// not held), and the SHA-256 of the whole file as read now (the rest streamed through the hash): what a
/// done-check hashing the file again compares with.
fn read_external(path: &Path, declared: u64) -> Result<(Vec<u8>, InputFile), String> {
    use std::io::Read;
    let mut file = std::fs::File::open(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => "file not found".to_string(),
        _ => e.to_string(),
    })?;
    let mut data = Vec::new();
    (&mut file).take(declared.saturating_add(4)).read_to_end(&mut data).map_err(|e| e.to_string())?;
    let mut hasher = Sha256::new_with_prefix(&data);
    let mut rest = vec![0u8; 1 << 16];
    loop {
        match file.read(&mut rest).map_err(|e| e.to_string())? {
            0 => break,
            n => hasher.update(&rest[..n]),
        }
    }
    Ok((data, InputFile::hashed(path, hasher)))
}

/// The files a `.gltf` / `.glb` at `path` names by relative URI (buffers, images, EXT_lights_ies profiles) that
/// exist, from its JSON alone (nothing decoded): what a farm checks each machine holds. A superset of what a load
/// reads (an unused image is listed too); empty when the file does not parse.
pub fn referenced_files(path: &Path) -> Vec<PathBuf> {
    let Ok(bytes) = std::fs::read(path) else { return Vec::new() };
    let mut warnings = Warnings { what: String::new(), list: Vec::new() };
    let Ok(json) = split(&bytes, "", &mut warnings).and_then(|c| parse_json(c.json, "")) else { return Vec::new() };
    let base = path.parent();
    let uris = ["/buffers", "/images", "/extensions/EXT_lights_ies/lights"].into_iter().flat_map(|list| {
        let items = json.pointer(list).and_then(Value::as_array).map(Vec::as_slice).unwrap_or_default();
        items.iter().filter_map(|item| item.get("uri").and_then(Value::as_str))
    });
    let mut files: Vec<PathBuf> = uris
        .filter_map(|uri| match resolve_uri(uri, base) {
            Ok(UriTarget::File(p)) if p.is_file() => Some(p),
            _ => None,
        })
        .collect();
    files.sort();
    files.dedup();
    files
}

/// A URI short enough for a message (data: URIs can be megabytes long).
pub(super) fn shorten(uri: &str) -> String {
    match uri.char_indices().nth(60) {
        Some((cut, _)) => format!("{}...", &uri[..cut]),
        None => uri.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uris() {
        assert!(has_scheme("https://example.com/a.bin"));
        assert!(!has_scheme("C:/models/a.bin"));
        assert!(!has_scheme("textures/a b.png"));
        assert_eq!(percent_decode("a%20b%2"), b"a b%2");
        match resolve_uri("data:application/octet-stream;base64,AAEC", None) {
            Ok(UriTarget::Data { bytes, mime }) => {
                assert_eq!(bytes, vec![0, 1, 2]);
                assert_eq!(mime, "application/octet-stream");
            }
            _ => panic!("data: URI not decoded"),
        }
        match resolve_uri("tex%20one.png", Some(Path::new("/m"))) {
            Ok(UriTarget::File(p)) => assert_eq!(p, Path::new("/m/tex one.png")),
            _ => panic!("relative URI not resolved"),
        }
        assert!(resolve_uri("a.bin", None).is_err());
    }
}
