//! Tiles and their provenance, as `kelvin merge` and a resumed batch read them: bytes ->
//! `read_exr_tile_from_bytes` and `read_exr_provenance_from_bytes`, then a merge of the tile with
//! itself split in two. An error is fine; a panic, or an accepted tile whose pixel count is not its
//! window's or whose window is not inside its image, is a crash.
#![no_main]

use kelvin::render::film_io::{read_exr_provenance_from_bytes, read_exr_tile_from_bytes};
use kelvin::render::tiles::merge_tiles;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = read_exr_provenance_from_bytes(data, "fuzz");
    let Ok(tile) = read_exr_tile_from_bytes(data, "fuzz") else { return };
    assert_eq!(tile.pixels.len(), tile.crop.pixels(), "pixel count");
    // Merging never panics, whatever the tile claims; a tile covering its image merges into it.
    if let Ok((w, h, rgb)) = merge_tiles(std::slice::from_ref(&tile)) {
        assert_eq!(rgb.len(), w as usize * h as usize);
        assert_eq!((tile.crop.x0, tile.crop.y0, tile.crop.x1, tile.crop.y1), (0, 0, w, h), "a partial cover merged");
    }
});
