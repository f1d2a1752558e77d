//! Environment maps: bytes -> `load_image_from_bytes` with the "hdr" and the "exr" hint -> `EnvMapTables::build`
//! (with MIS compensation) and a sample and pdf from the tables. A load error is fine; a panic, or a loaded image
//! breaking the loader's documented promises (size, pixel count, finite non-negative pixels), is a crash.
//!
//! The loader catches panics inside the decoders and reports them as `ImageError::Decode` (documented); such
//! panics are printed once per location by the hook below, so they can be looked at, but are not crashes.
#![no_main]

use std::collections::HashSet;
use std::sync::{Mutex, Once};

use glam::{Vec2, Vec3};
use kelvin::light::EnvMapTables;
use kelvin::scene::image::load_image_from_bytes;
use libfuzzer_sys::fuzz_target;

/// Tables of images above this many pixels are not built: a tiny RLE file can legitimately describe a huge
/// map, and the fuzzer would spend its time (and memory) on one input.
const MAX_TABLE_PIXELS: usize = 1 << 22;

fn report_caught_panics_once() {
    static HOOK: Once = Once::new();
    static SEEN: Mutex<Option<HashSet<String>>> = Mutex::new(None);
    HOOK.call_once(|| {
        // Replaces libfuzzer-sys's aborting hook: a panic that escapes the target still aborts (libfuzzer-sys
        // checks catch_unwind around the target), one the loader catches does not.
        std::panic::set_hook(Box::new(|info| {
            let at = info.location().map(|l| l.to_string()).unwrap_or_default();
            let mut seen = SEEN.lock().unwrap_or_else(|e| e.into_inner());
            if seen.get_or_insert_with(HashSet::new).insert(at.clone()) {
                eprintln!("panic (caught by the loader?) at {at}: {info}");
            }
        }));
    });
}

fuzz_target!(|data: &[u8]| {
    report_caught_panics_once();
    for hint in ["hdr", "exr"] {
        let Ok(loaded) = load_image_from_bytes(data, hint, "fuzz") else { continue };
        let image = loaded.image;
        assert!(image.width > 0 && image.height > 0, "zero size");
        assert_eq!(image.pixels.len(), image.width * image.height, "pixel count");
        assert!(image.pixels.iter().all(|p| p.is_finite() && p.cmpge(Vec3::ZERO).all()), "bad pixel");
        if image.pixels.len() > MAX_TABLE_PIXELS {
            continue;
        }
        let tables = EnvMapTables::build(&image, true);
        for mis in [false, true] {
            if let Some((dir, pdf)) = tables.sample_direction(Vec2::new(0.3, 0.7), mis) {
                assert!(dir.is_finite() && pdf.is_finite() && pdf > 0.0, "sample {dir} pdf {pdf}");
                let _ = tables.pdf_direction(dir, mis);
            }
        }
    }
});
