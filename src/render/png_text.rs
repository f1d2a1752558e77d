//! A PNG's `tEXt` chunks (PNG specification, sections 5.3 and 11.3.4.3): one added to encoded
//! bytes, one read back with every chunk's CRC checked, so that a PNG carries its provenance in
//! the file itself, as an EXR does in its header.

/// The PNG signature.
const SIGNATURE: &[u8; 8] = b"\x89PNG\r\n\x1a\n";

/// CRC-32 of the PNG specification (ISO 3309, polynomial 0xEDB88320 reflected), over `parts` in turn.
fn crc32(parts: &[&[u8]]) -> u32 {
    let mut crc = !0u32;
    for byte in parts.iter().flat_map(|p| p.iter()) {
        crc ^= *byte as u32;
        for _ in 0..8 {
            crc = if crc & 1 != 0 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
        }
    }
    !crc
}

/// The chunks of `png` as (type, data), each CRC checked; or what is wrong.
fn chunks(png: &[u8]) -> Result<Vec<([u8; 4], &[u8])>, String> {
    let mut rest = png.strip_prefix(SIGNATURE).ok_or("not a PNG (no signature)")?;
    let mut out = Vec::new();
    while !rest.is_empty() {
        let (Some(len), Some(kind)) = (rest.get(..4), rest.get(4..8)) else {
            return Err(format!("chunk {} cut short", out.len()));
        };
        let len = u32::from_be_bytes(len.try_into().expect("4 bytes")) as usize;
        let kind: [u8; 4] = kind.try_into().expect("4 bytes");
        let Some(data) = rest.get(8..8 + len) else { return Err(format!("chunk {} cut short", out.len())) };
        let Some(crc) = rest.get(8 + len..12 + len) else { return Err(format!("chunk {} cut short", out.len())) };
        if crc32(&[&kind, data]).to_be_bytes() != crc {
            return Err(format!("chunk {} ({}) fails its CRC", out.len(), String::from_utf8_lossy(&kind)));
        }
        out.push((kind, data));
        rest = &rest[12 + len..];
        if &kind == b"IEND" {
            break;
        }
    }
    if out.last().is_none_or(|(k, _)| k != b"IEND") {
        return Err("no IEND chunk: cut short".into());
    }
    Ok(out)
}

/// `png` with a `tEXt` chunk `keyword` = `text` before its IEND chunk (`png` as an encoder wrote it).
pub(super) fn with_text(png: &[u8], keyword: &str, text: &str) -> Vec<u8> {
    let mut data = Vec::with_capacity(keyword.len() + 1 + text.len());
    data.extend_from_slice(keyword.as_bytes());
    data.push(0);
    // tEXt is Latin-1: other characters go in as JSON's \u escapes, as in an EXR's attribute.
    for c in text.chars() {
        if c.is_ascii() {
            data.push(c as u8);
        } else {
            c.encode_utf16(&mut [0; 2]).iter().for_each(|u| data.extend(format!("\\u{u:04x}").bytes()));
        }
    }
    // IEND is the last 12 bytes of an encoder's output.
    let at = png.len().saturating_sub(12);
    let mut out = Vec::with_capacity(png.len() + data.len() + 12);
    out.extend_from_slice(&png[..at]);
    out.extend_from_slice(&(data.len() as u32).to_be_bytes());
    out.extend_from_slice(b"tEXt");
    out.extend_from_slice(&data);
    out.extend_from_slice(&crc32(&[b"tEXt", &data]).to_be_bytes());
    out.extend_from_slice(&png[at..]);
    out
}

/// The text of the `tEXt` chunk `keyword` in `png` (None: there is none); an error if the file is
/// not a whole PNG.
pub(super) fn text(png: &[u8], keyword: &str) -> Result<Option<String>, String> {
    for (kind, data) in chunks(png)? {
        if &kind == b"tEXt"
            && let Some(text) = data.strip_prefix(keyword.as_bytes()).and_then(|d| d.strip_prefix(&[0]))
        {
            return Ok(Some(text.iter().map(|&b| b as char).collect()));
        }
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The CRC of "IEND" with no data, as every PNG ends (0xAE426082).
    #[test]
    fn crc_of_iend() {
        assert_eq!(crc32(&[b"IEND"]), 0xAE42_6082);
    }
}
