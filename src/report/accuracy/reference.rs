//! Converged references, rendered once and cached under the output folder as
//! `reference-<scene>-<mode>-<hash>.exr` (linear f32, read back bit-exact) with a `.json` beside
//! it holding the render time. The hash covers the scene, the configuration, the size, the seed
//! and [`REFERENCE_VERSION`]; delete the files (or bump the version) after changing the renderer.

use std::path::{Path, PathBuf};

use glam::Vec3;

use super::knobs::Config;
use super::{AccuracyError, scenes::BuiltScene};
use crate::render::film_io::{read_exr, write_exr};
use crate::render::renderer::render;
use crate::shading::ColorMode;

/// Bump to invalidate every cached reference.
pub const REFERENCE_VERSION: u32 = 1;
/// Seed of reference renders; sweeps use seeds 1, 2, ... so their samples are independent of it.
pub const REFERENCE_SEED: u64 = 0x7e6e_7e6e_0000_0001;

/// A reference image and where it came from.
#[derive(Clone, Debug)]
pub struct Reference {
    /// Linear RGB pixels, row-major.
    pub pixels: Vec<Vec3>,
    /// Samples per pixel it was rendered with.
    pub spp: u32,
    /// Colour mode it was rendered in.
    pub color: ColorMode,
    /// Time of the render that made it, s.
    pub seconds: f64,
    /// The cached EXR file.
    pub path: PathBuf,
    /// True when read from the cache.
    pub cached: bool,
}

/// FNV-1a, 64 bit: a stable hash of the cache key (std's hasher may change between releases).
fn fnv1a(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x0100_0000_01b3))
}

/// The reference of `scene` for `config` (whose `spp` is the reference's) at `width` x `height`:
/// read from `out` when cached there, else rendered and written.
pub fn reference(
    scene: &mut BuiltScene,
    config: &Config,
    width: u32,
    height: u32,
    out: &Path,
    progress: &mut dyn FnMut(&str),
) -> Result<Reference, AccuracyError> {
    let key = format!(
        "v{REFERENCE_VERSION} | {} | {config:?} | {width}x{height} | seed {REFERENCE_SEED}",
        scene.id.describe()
    );
    let mode = if config.color == ColorMode::Spectral { "spectral" } else { "rgb" };
    let path = out.join(format!("reference-{}-{mode}-{:016x}.exr", scene.id.name(), fnv1a(&key)));
    let meta = path.with_extension("json");
    if let Some((pixels, seconds)) = read_cached(&path, &meta, width, height) {
        progress(&format!("  reference {} (cached)", path.display()));
        return Ok(Reference { pixels, spp: config.spp, color: config.color, seconds, path, cached: true });
    }
    progress(&format!("  rendering reference {} at {} spp ...", path.display(), config.spp));
    config.apply(&mut scene.world, REFERENCE_SEED);
    let (film, stats) = render(&mut scene.world, &mut scene.schedule, &config.render_options(width, height), |_| {});
    let pixels = film.pixels();
    write_exr(&path, width as usize, height as usize, &pixels)?;
    let json = serde_json::json!({ "key": key, "seconds": stats.seconds, "spp": config.spp });
    std::fs::write(&meta, serde_json::to_string_pretty(&json).unwrap_or_default())
        .map_err(|e| AccuracyError::Io { path: meta.display().to_string(), msg: e.to_string() })?;
    progress(&format!("  reference done in {:.1} s", stats.seconds));
    Ok(Reference { pixels, spp: config.spp, color: config.color, seconds: stats.seconds, path, cached: false })
}

/// The cached image and its render time, if both files are there and the image has the size.
fn read_cached(path: &Path, meta: &Path, width: u32, height: u32) -> Option<(Vec<Vec3>, f64)> {
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(meta).ok()?).ok()?;
    let seconds = json.get("seconds")?.as_f64()?;
    let (w, h, pixels) = read_exr(path).ok()?;
    (w == width as usize && h == height as usize).then_some((pixels, seconds))
}
