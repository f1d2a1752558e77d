//! Bakes split into parts: part k of n bakes a contiguous range of the bake's cells (covered
//! texels of every lightmap in order, or voxel sides) with every sample those cells would get in
//! the whole bake. A cell's random streams are keyed by its ordinal and its samples are summed in
//! order, so the sums of the parts, joined, are bit for bit the whole bake's: a farm bakes the
//! parts anywhere and one merge finishes the maps (dilation needs all of them).
//!
//! A part file is `MAGIC`, a little-endian u32 length, a JSON header (the range, samples, counts,
//! warnings, and a caller's provenance that a merge compares), then per cell three f64 sums, three
//! f64 sums of squares and two u32 counts, little-endian, then the SHA-256 of everything before it
//! (32 bytes): a part copied between machines with a bit flipped is refused, not merged.

use std::ops::Range;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::BakeError;
use super::lightmap::Accumulator;
use crate::render::renderer::RenderStats;

/// The first bytes of a part file.
pub const MAGIC: &[u8; 16] = b"kelvin bake part";
/// The version of the part format this build writes and reads (2: with the checksum).
const FORMAT: u32 = 2;
/// Bytes of the trailing checksum (SHA-256).
const CHECKSUM_BYTES: usize = 32;
/// Bytes per cell after the header.
const CELL_BYTES: usize = 6 * 8 + 2 * 4;

/// Part `index` (from 0) of `count` equal ranges of a bake's cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Part {
    /// From 0.
    pub index: u32,
    /// Parts in all.
    pub count: u32,
}

impl Part {
    /// The whole bake as one part.
    pub const WHOLE: Part = Part { index: 0, count: 1 };

    /// Its range of `cells` cells: part k of n holds cells [k cells / n, (k + 1) cells / n).
    pub fn range(&self, cells: u64) -> Range<u64> {
        let at = |k: u32| (cells as u128 * k as u128 / self.count as u128) as u64;
        at(self.index)..at(self.index + 1)
    }

    pub(super) fn check(&self) -> Result<(), BakeError> {
        if self.count == 0 || self.index >= self.count {
            return Err(BakeError::Invalid(format!(
                "part {} of {}: need 1 <= part <= count",
                self.index + 1,
                self.count
            )));
        }
        Ok(())
    }
}

impl std::str::FromStr for Part {
    type Err = String;

    /// "K/N": part K (from 1) of N.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let (k, n) = s.split_once('/').ok_or_else(|| format!("part {s:?}: expected K/N, e.g. 2/8"))?;
        let number = |t: &str| t.trim().parse::<u32>().map_err(|e| format!("part {s:?}: {t:?}: {e}"));
        let (k, n) = (number(k)?, number(n)?);
        if n == 0 || k == 0 || k > n {
            return Err(format!("part {s:?}: need 1 <= K <= N"));
        }
        Ok(Part { index: k - 1, count: n })
    }
}

/// What a part file's header says.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
struct Header {
    format: u32,
    /// "lightmaps" or "volume".
    kind: String,
    part: u32,
    parts: u32,
    /// The bake's cells, and this part's range of them.
    cells: u64,
    first: u64,
    end: u64,
    spp: u64,
    seconds: f64,
    camera_samples: u64,
    shadow_rays: u64,
    bsdf_rays: u64,
    warnings: Vec<String>,
    /// What the caller says made this part (scene, settings, build); merges compare it.
    provenance: serde_json::Value,
}

/// The per-cell sums of one part of a bake.
#[derive(Clone, Debug)]
pub struct BakePart {
    header: Header,
    pub(super) sums: Vec<Accumulator>,
}

impl BakePart {
    pub(super) fn new(kind: &str, part: Part, cells: u64, sums: Vec<Accumulator>, stats: &RenderStats) -> Self {
        let range = part.range(cells);
        debug_assert_eq!(sums.len() as u64, range.end - range.start);
        let header = Header {
            format: FORMAT,
            kind: kind.to_owned(),
            part: part.index,
            parts: part.count,
            cells,
            first: range.start,
            end: range.end,
            spp: stats.spp,
            seconds: stats.seconds,
            camera_samples: stats.camera_samples,
            shadow_rays: stats.shadow_rays,
            bsdf_rays: stats.bsdf_rays,
            warnings: stats.report.warnings.clone(),
            provenance: serde_json::Value::Null,
        };
        Self { header, sums }
    }

    /// Which part of how many this is.
    pub fn part(&self) -> Part {
        Part { index: self.header.part, count: self.header.parts }
    }

    /// What the caller recorded as having made the part (null unless set).
    pub fn provenance(&self) -> &serde_json::Value {
        &self.header.provenance
    }

    /// Records what made the part (scene and settings), for [`check_provenance`] at the merge.
    pub fn set_provenance(&mut self, provenance: serde_json::Value) {
        self.header.provenance = provenance;
    }

    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let header = serde_json::to_vec(&self.header).unwrap_or_default();
        let mut out = Vec::with_capacity(MAGIC.len() + 4 + header.len() + self.sums.len() * CELL_BYTES);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&(header.len() as u32).to_le_bytes());
        out.extend_from_slice(&header);
        for a in &self.sums {
            let (sum, sum2) = a.sums();
            for v in sum.to_array().into_iter().chain(sum2.to_array()) {
                out.extend_from_slice(&v.to_le_bytes());
            }
            let (valid, leaked) = a.counts();
            out.extend_from_slice(&valid.to_le_bytes());
            out.extend_from_slice(&leaked.to_le_bytes());
        }
        let checksum = checksum(&out);
        out.extend_from_slice(&checksum);
        out
    }

    /// Reads a part file's bytes; `what` names it in errors.
    pub fn from_bytes(bytes: &[u8], what: &str) -> Result<Self, BakeError> {
        let bad = |why: String| BakeError::Invalid(format!("{what}: not a kelvin bake part: {why}"));
        let rest = bytes.strip_prefix(MAGIC.as_slice()).ok_or_else(|| bad("wrong magic".into()))?;
        // Checked first: nothing of a damaged file is trusted, its header included.
        let body = bytes.len().checked_sub(CHECKSUM_BYTES).filter(|&n| n >= MAGIC.len());
        let body = body.ok_or_else(|| bad("truncated (no checksum)".into()))?;
        if checksum(&bytes[..body]) != bytes[body..] {
            return Err(BakeError::Invalid(format!(
                "{what}: corrupt bake part: its checksum does not match its bytes (damaged or cut short)"
            )));
        }
        let rest = &rest[..rest.len() - CHECKSUM_BYTES];
        let (len, rest) = rest.split_first_chunk::<4>().ok_or_else(|| bad("truncated header".into()))?;
        let len = u32::from_le_bytes(*len) as usize;
        let (json, cells) = rest.split_at_checked(len).ok_or_else(|| bad("truncated header".into()))?;
        let header: Header = serde_json::from_slice(json).map_err(|e| bad(format!("header: {e}")))?;
        if header.format != FORMAT {
            return Err(bad(format!("format {} (this build reads {FORMAT})", header.format)));
        }
        let part = Part { index: header.part, count: header.parts };
        if part.check().is_err() || part.range(header.cells) != (header.first..header.end) {
            return Err(bad(format!(
                "part {} of {} does not hold cells {}..{} of {}",
                header.part + 1,
                header.parts,
                header.first,
                header.end,
                header.cells
            )));
        }
        let count = header.end - header.first;
        if header.end > header.cells || count.checked_mul(CELL_BYTES as u64) != Some(cells.len() as u64) {
            return Err(bad(format!(
                "{} bytes of cells for cells {}..{} of {}",
                cells.len(),
                header.first,
                header.end,
                header.cells
            )));
        }
        let sums = cells
            .chunks_exact(CELL_BYTES)
            .map(|c| {
                let f = |i: usize| f64::from_le_bytes(c[8 * i..8 * i + 8].try_into().expect("8 bytes"));
                let u = |i: usize| u32::from_le_bytes(c[48 + 4 * i..52 + 4 * i].try_into().expect("4 bytes"));
                Accumulator::from_parts(DVec3::new(f(0), f(1), f(2)), DVec3::new(f(3), f(4), f(5)), u(0), u(1))
            })
            .collect();
        Ok(Self { header, sums })
    }
}

/// Joins `parts` of a `kind` bake of `cells` cells into the sums of every cell and the stats of
/// the whole (seconds, samples and rays summed; warnings once each). Every cell must be in
/// exactly one part, every part must have the same samples per cell and the same provenance.
pub(super) fn join(
    kind: &str,
    cells: u64,
    mut parts: Vec<BakePart>,
) -> Result<(Vec<Accumulator>, RenderStats), BakeError> {
    let invalid = |msg: String| Err(BakeError::Invalid(msg));
    if parts.is_empty() {
        return invalid("no parts to merge".into());
    }
    parts.sort_by_key(|p| p.header.first);
    let first = &parts[0].header;
    let mut stats = RenderStats { spp: first.spp, ..RenderStats::default() };
    let mut sums = Vec::with_capacity(cells as usize);
    let mut next = 0;
    for p in &parts {
        let h = &p.header;
        let name = format!("part {} of {}", h.part + 1, h.parts);
        if h.kind != kind || h.cells != cells {
            return invalid(format!(
                "{name} is of a {} bake of {} cells, not a {kind} bake of {cells}",
                h.kind, h.cells
            ));
        }
        if h.spp != first.spp {
            return invalid(format!("{name} has {} samples per cell, part {} {}", h.spp, first.part + 1, first.spp));
        }
        check_provenance(&first.provenance, &h.provenance).map_err(|f| {
            BakeError::Invalid(format!("{name} was made differently from part {}: {f}", first.part + 1))
        })?;
        match h.first.cmp(&next) {
            std::cmp::Ordering::Less => return invalid(format!("{name} overlaps another part at cell {}", h.first)),
            std::cmp::Ordering::Greater => return invalid(format!("cells {next}..{} are in no part", h.first)),
            std::cmp::Ordering::Equal => {}
        }
        next = h.end;
        sums.extend_from_slice(&p.sums);
        stats.seconds += h.seconds;
        stats.camera_samples += h.camera_samples;
        stats.shadow_rays += h.shadow_rays;
        stats.bsdf_rays += h.bsdf_rays;
        for w in &h.warnings {
            if !stats.report.warnings.contains(w) {
                stats.report.warnings.push(w.clone());
            }
        }
    }
    if next != cells {
        return invalid(format!("cells {next}..{cells} are in no part"));
    }
    Ok((sums, stats))
}

/// The SHA-256 of `bytes`, a part file's checksum.
fn checksum(bytes: &[u8]) -> [u8; CHECKSUM_BYTES] {
    use sha2::Digest;
    sha2::Sha256::digest(bytes).as_slice().try_into().expect("SHA-256 is 32 bytes")
}

/// Ok if `a` and `b` record the same provenance; otherwise the first field (as a JSON path) where
/// they differ and both values.
pub fn check_provenance(a: &serde_json::Value, b: &serde_json::Value) -> Result<(), String> {
    fn walk(a: &serde_json::Value, b: &serde_json::Value, path: &str) -> Result<(), String> {
        use serde_json::Value::Object;
        match (a, b) {
            (Object(x), Object(y)) => {
                for key in x.keys().chain(y.keys().filter(|k| !x.contains_key(*k))) {
                    let none = serde_json::Value::Null;
                    walk(x.get(key).unwrap_or(&none), y.get(key).unwrap_or(&none), &format!("{path}/{key}"))?;
                }
                Ok(())
            }
            _ if a == b => Ok(()),
            _ => Err(format!("{} is {a} against {b}", if path.is_empty() { "/" } else { path })),
        }
    }
    walk(a, b, "")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parts 1..n of any cell count tile it: consecutive, none empty when cells >= n.
    #[test]
    fn parts_tile_the_cells() {
        for (cells, n) in [(0u64, 3u32), (10, 3), (7, 7), (1_000_003, 16), (u32::MAX as u64 * 6, 5)] {
            let mut next = 0;
            for index in 0..n {
                let r = Part { index, count: n }.range(cells);
                assert_eq!(r.start, next);
                assert!(cells < n as u64 || r.end > r.start);
                next = r.end;
            }
            assert_eq!(next, cells);
        }
        assert_eq!("2/8".parse::<Part>(), Ok(Part { index: 1, count: 8 }));
        for bad in ["0/8", "9/8", "1/0", "3", "a/b"] {
            assert!(bad.parse::<Part>().is_err(), "{bad}");
        }
    }

    /// A part survives its file bit for bit; a truncated or foreign file is an error.
    #[test]
    fn part_files_round_trip() {
        let mut a = Accumulator::default();
        a.add(DVec3::new(0.1, 1e-300, 3e5), false);
        a.add(DVec3::ONE, true);
        let stats = RenderStats { spp: 4, seconds: 1.5, ..RenderStats::default() };
        let mut part = BakePart::new("volume", Part { index: 1, count: 2 }, 4, vec![a, Accumulator::default()], &stats);
        part.set_provenance(serde_json::json!({ "scene": "x.glb", "settings": { "spp": 4 } }));
        let bytes = part.to_bytes();
        let back = BakePart::from_bytes(&bytes, "p").unwrap();
        assert_eq!(back.header, part.header);
        assert_eq!(back.to_bytes(), bytes);
        assert!(BakePart::from_bytes(&bytes[..bytes.len() - 1], "p").is_err());
        assert!(BakePart::from_bytes(b"kelvin bake partXXXX", "p").is_err());
        assert!(BakePart::from_bytes(b"PK\x03\x04", "p").is_err());
    }

    #[test]
    fn provenance_names_the_differing_field() {
        let a = serde_json::json!({ "scene": "x.glb", "settings": { "spp": 4, "seed": 1 } });
        let b = serde_json::json!({ "scene": "x.glb", "settings": { "spp": 4, "seed": 2 } });
        assert_eq!(check_provenance(&a, &a), Ok(()));
        assert_eq!(check_provenance(&a, &b), Err("/settings/seed is 1 against 2".into()));
    }
}
