//! Bake jobs in a batch manifest:
//!
//! ```json
//! { "name": "cornell maps", "bake": "lightmaps", "scene": "cornell.glb", "output": "baked/cornell",
//!   "parts": 4, "settings": { "size": 256, "spp": 128, "env": "sky.hdr", "light": "indirect" } }
//! ```
//!
//! `bake` is `lightmaps` or `volume`; each key of `settings` is a flag of that `kelvin bake`
//! command (`max_depth` is `--max-depth`; arrays are comma-separated, `true` is a bare flag), so
//! a job means what the command means and is checked by its parser. `parts` splits the bake into
//! that many texel ranges that any machine bakes (`--part K/N`) and one merge joins bit for bit.

use std::path::Path;

use serde_json::Value;

use super::bake::{BakeArgs, parse};

/// Keys of a bake job.
const KEYS: [&str; 6] = ["name", "bake", "scene", "output", "parts", "settings"];
/// Flags a batch sets itself.
pub(super) const RESERVED: [&str; 4] = ["output", "part", "merge", "threads"];
/// Most parts a bake may be split into.
pub(super) const MAX_PARTS: u64 = 4096;

/// A bake job's `kelvin bake` arguments (without `-o`), its output and the parts it is split into.
pub(super) struct BakeJob {
    pub(super) args: Vec<String>,
    pub(super) parsed: BakeArgs,
    pub(super) parts: u32,
}

/// Reads a bake job; `output` is its resolved output path.
pub(super) fn resolve(job: &Value, base: &Path, output: &Path) -> Result<BakeJob, String> {
    let object = job.as_object().ok_or("a job is a JSON object")?;
    if let Some(key) = object.keys().find(|k| !KEYS.contains(&k.as_str())) {
        return Err(format!("unknown key {key:?} in a bake job (keys: {})", KEYS.join(", ")));
    }
    let kind = match job["bake"].as_str() {
        Some(k @ ("lightmaps" | "volume")) => k,
        _ => return Err(format!("bake: {} is not \"lightmaps\" or \"volume\"", job["bake"])),
    };
    if kind == "volume" && output.extension().is_none_or(|e| !e.eq_ignore_ascii_case("ktx2")) {
        return Err(format!("output {}: a volume is written as .ktx2", output.display()));
    }
    let parts = match job.get("parts") {
        None => 1,
        Some(v) => v
            .as_u64()
            .filter(|n| (1..=MAX_PARTS).contains(n))
            .ok_or_else(|| format!("parts: {v} is not a whole number in 1..={MAX_PARTS}"))? as u32,
    };
    let scene = job["scene"].as_str().ok_or("a bake job needs its scene")?;
    let scene = base.join(scene);
    if !scene.is_file() {
        return Err(format!("scene {}: no such file", scene.display()));
    }
    let mut args = vec![kind.to_owned(), scene.display().to_string()];
    let settings = match job.get("settings") {
        None => serde_json::Map::new(),
        Some(Value::Object(m)) => m.clone(),
        Some(v) => return Err(format!("settings: {v} is not an object of `kelvin bake {kind}` flags")),
    };
    args.extend(super::settings::flags(&settings, &RESERVED, base)?);
    let with_output = |extra: &[String]| {
        let argv: Vec<String> = args
            .iter()
            .cloned()
            .chain(extra.iter().cloned())
            .chain(["-o".into(), output.display().to_string()])
            .collect();
        parse(&argv)
    };
    // A split is checked as its parts will run (a time budget, say, cannot be split).
    if parts > 1 {
        with_output(&["--part".into(), format!("1/{parts}")])?;
    }
    let parsed = with_output(&[])?;
    Ok(BakeJob { args, parsed, parts })
}
