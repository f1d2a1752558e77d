//! Tiles of an image: the crop a render is limited to, and the merge of tile renders back into the
//! full image with a check that they cover it exactly once.
//!
//! A crop renders the same camera rays and random streams as the full image (pixel ids are the
//! full image's), so a tile's pixels equal the same region of the full render bit for bit.

use super::job::MAX_SIDE;
use glam::Vec3;

/// A rectangle of pixels `x0..x1` by `y0..y1` (exclusive ends) of a full image, row 0 at the top.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Crop {
    /// First column, pixels.
    pub x0: u32,
    /// First row, pixels from the top.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
}

/// Why a crop or a set of tiles was refused.
#[derive(Debug, thiserror::Error, Clone, PartialEq, Eq)]
pub enum TileError {
    /// A crop string is not four comma-separated whole numbers.
    #[error("crop '{given}': expected four whole numbers X0,Y0,X1,Y1 (pixels, X1 and Y1 exclusive)")]
    Syntax {
        /// The string as given.
        given: String,
    },
    /// A crop covers no pixel: `x1 <= x0` or `y1 <= y0`.
    #[error("crop {crop} is empty: X1 must be greater than X0 and Y1 greater than Y0")]
    Empty {
        /// The empty crop.
        crop: Crop,
    },
    /// A crop reaches past the right or bottom edge of the image ([`Crop::check`]).
    #[error("crop {crop} is not inside the {width}x{height} image")]
    Outside {
        /// The crop.
        crop: Crop,
        /// Image width, pixels.
        width: u32,
        /// Image height, pixels.
        height: u32,
    },
    /// A tile claims a full image larger than kelvin renders (a side above [`MAX_SIDE`]).
    #[error("{tile}: it claims a {width}x{height} image; kelvin's images are at most {MAX_SIDE} pixels a side")]
    TooLarge {
        /// Name of the tile.
        tile: String,
        /// Width of its full image, pixels.
        width: u32,
        /// Height of its full image, pixels.
        height: u32,
    },
    /// A tile to merge belongs to a full image of another size than the first tile's.
    #[error(
        "{tile}: it belongs to a {width}x{height} image, but {first} belongs to a {first_width}x{first_height} one"
    )]
    ImageSize {
        /// Name of the tile.
        tile: String,
        /// Width of its full image, pixels.
        width: u32,
        /// Height of its full image, pixels.
        height: u32,
        /// Name of the first tile.
        first: String,
        /// Width of the first tile's full image, pixels.
        first_width: u32,
        /// Height of the first tile's full image, pixels.
        first_height: u32,
    },
    /// A tile to merge has an empty region or one not inside its full image.
    #[error("{tile}: region {crop} is not inside its {width}x{height} image")]
    TileOutside {
        /// Name of the tile.
        tile: String,
        /// Its region.
        crop: Crop,
        /// Full image width, pixels.
        width: u32,
        /// Full image height, pixels.
        height: u32,
    },
    /// Two tiles to merge cover the same pixel.
    #[error("{tile} and {other} overlap (both cover pixel {x},{y})")]
    Overlap {
        /// Name of the later tile.
        tile: String,
        /// Name of the earlier tile that already covers the pixel.
        other: String,
        /// Column of the first shared pixel.
        x: u32,
        /// Row of the first shared pixel.
        y: u32,
    },
    /// The merged tiles leave pixels of the full image uncovered.
    #[error("{count} pixels of the {width}x{height} image are in no tile, within {region} (e.g. pixel {x},{y})")]
    Gap {
        /// Number of uncovered pixels.
        count: u64,
        /// Full image width, pixels.
        width: u32,
        /// Full image height, pixels.
        height: u32,
        /// Bounding box of the uncovered pixels.
        region: Crop,
        /// Column of the first uncovered pixel (row-major order).
        x: u32,
        /// Row of the first uncovered pixel.
        y: u32,
    },
    /// A tile's pixel list does not match the size of its region.
    #[error("{tile}: {len} pixels for a {crop} region")]
    PixelCount {
        /// Name of the tile.
        tile: String,
        /// Number of pixels it holds.
        len: usize,
        /// Its region.
        crop: Crop,
    },
    /// [`merge_tiles`] was given an empty list.
    #[error("no tiles to merge")]
    NoTiles,
    /// A crop was asked of a ReSTIR render with spatial reuse, whose tiles would not match the
    /// full render.
    #[error(
        "ReSTIR's spatial reuse takes reservoirs of the render's own samples, so a tile would not be that region \
         of the full image: render ReSTIR images with neighbours whole, or tile with --neighbours 0 or the ris \
         light sampler"
    )]
    Reuse,
    /// A crop was asked of a render with a time budget, whose tiles would differ in samples per pixel.
    #[error(
        "a time budget renders as many passes as fit, so tiles would differ in samples per pixel: give tiles \
         a sample count, not a time"
    )]
    TimeBudget,
}

impl std::fmt::Display for Crop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{},{},{},{}", self.x0, self.y0, self.x1, self.y1)
    }
}

impl std::str::FromStr for Crop {
    type Err = TileError;

    /// `X0,Y0,X1,Y1`; the crop must not be empty.
    fn from_str(s: &str) -> Result<Self, TileError> {
        let v: Result<Vec<u32>, _> = s.split(',').map(|c| c.trim().parse()).collect();
        match v.as_deref() {
            Ok(&[x0, y0, x1, y1]) => Self::new(x0, y0, x1, y1),
            _ => Err(TileError::Syntax { given: s.into() }),
        }
    }
}

impl Crop {
    /// A non-empty crop.
    pub fn new(x0: u32, y0: u32, x1: u32, y1: u32) -> Result<Self, TileError> {
        let crop = Self { x0, y0, x1, y1 };
        if x1 <= x0 || y1 <= y0 { Err(TileError::Empty { crop }) } else { Ok(crop) }
    }

    /// The whole of a `width` x `height` image.
    pub fn full(width: u32, height: u32) -> Self {
        Self { x0: 0, y0: 0, x1: width, y1: height }
    }

    /// Width in pixels (0 if inverted).
    pub fn width(&self) -> u32 {
        self.x1.saturating_sub(self.x0)
    }

    /// Height in pixels (0 if inverted).
    pub fn height(&self) -> u32 {
        self.y1.saturating_sub(self.y0)
    }

    /// Number of pixels.
    pub fn pixels(&self) -> usize {
        self.width() as usize * self.height() as usize
    }

    /// Whether the crop is non-empty and inside a `width` x `height` image.
    pub fn check(&self, width: u32, height: u32) -> Result<(), TileError> {
        Self::new(self.x0, self.y0, self.x1, self.y1)?;
        if self.x1 > width || self.y1 > height {
            return Err(TileError::Outside { crop: *self, width, height });
        }
        Ok(())
    }

    /// The part of the crop inside a `width` x `height` image (empty if none is).
    pub fn clipped(&self, width: u32, height: u32) -> Self {
        let (x1, y1) = (self.x1.min(width), self.y1.min(height));
        Self { x0: self.x0.min(x1), y0: self.y0.min(y1), x1, y1 }
    }
}

/// One rendered tile: its region of a `width` x `height` image and its pixels (row-major, the
/// region's size). `name` says where it came from, for errors.
#[derive(Clone, Debug, PartialEq)]
pub struct Tile {
    /// Where the tile came from (e.g. its file name), for errors.
    pub name: String,
    /// Width of the full image, pixels.
    pub width: u32,
    /// Height of the full image, pixels.
    pub height: u32,
    /// The tile's region of the full image.
    pub crop: Crop,
    /// The region's pixels, row-major from its top left.
    pub pixels: Vec<Vec3>,
}

/// Assembles tiles into their full image (width, height, row-major pixels). The tiles must belong
/// to one image size, lie inside it, and cover every pixel exactly once.
pub fn merge_tiles(tiles: &[Tile]) -> Result<(u32, u32, Vec<Vec3>), TileError> {
    let first = tiles.first().ok_or(TileError::NoTiles)?;
    let (width, height) = (first.width, first.height);
    // The full image is allocated from what the tiles claim: a few bytes could claim gigapixels.
    if width > MAX_SIDE || height > MAX_SIDE {
        return Err(TileError::TooLarge { tile: first.name.clone(), width, height });
    }
    for tile in tiles {
        if (tile.width, tile.height) != (width, height) {
            return Err(TileError::ImageSize {
                tile: tile.name.clone(),
                width: tile.width,
                height: tile.height,
                first: first.name.clone(),
                first_width: width,
                first_height: height,
            });
        }
        let crop = tile.crop;
        if crop.check(width, height).is_err() {
            return Err(TileError::TileOutside { tile: tile.name.clone(), crop, width, height });
        }
        if tile.pixels.len() != crop.pixels() {
            return Err(TileError::PixelCount { tile: tile.name.clone(), len: tile.pixels.len(), crop });
        }
    }
    // Gaps and overlaps come from the crops alone, before the image is allocated, so that a small
    // tile claiming a huge image costs no more than its own pixels.
    let (gap, overlap) = cover(tiles, width, height);
    if let Some((t, other, x, y)) = overlap {
        return Err(TileError::Overlap { tile: tiles[t].name.clone(), other: tiles[other].name.clone(), x, y });
    }
    if let Some((count, region, (x, y))) = gap {
        return Err(TileError::Gap { count, width, height, region, x, y });
    }
    let mut pixels = vec![Vec3::ZERO; width as usize * height as usize];
    for tile in tiles {
        let crop = tile.crop;
        for (row, src) in (crop.y0..crop.y1).zip(tile.pixels.chunks(crop.width() as usize)) {
            let start = row as usize * width as usize + crop.x0 as usize;
            pixels[start..start + crop.width() as usize].copy_from_slice(src);
        }
    }
    Ok((width, height, pixels))
}

/// How the tiles' crops cover a `width` x `height` image: the uncovered pixels (their count,
/// bounding box and first one in row-major order), and the first pixel in row-major order that two
/// tiles cover (the later tile's index, the earlier's, x, y); None for none. Swept over bands of
/// rows that the same crops cross, without a per-pixel map.
#[allow(clippy::type_complexity)]
fn cover(
    tiles: &[Tile],
    width: u32,
    height: u32,
) -> (Option<(u64, Crop, (u32, u32))>, Option<(usize, usize, u32, u32)>) {
    let mut edges: Vec<u32> = tiles.iter().flat_map(|t| [t.crop.y0, t.crop.y1]).chain([0, height]).collect();
    edges.sort_unstable();
    edges.dedup();
    let (mut gap, mut overlap): (Option<(u64, Crop, (u32, u32))>, _) = (None, None);
    for band in edges.windows(2) {
        let (y0, y1) = (band[0], band[1]);
        let mut spans: Vec<(u32, u32, usize)> = (tiles.iter().enumerate())
            .filter(|(_, t)| t.crop.y0 <= y0 && y1 <= t.crop.y1)
            .map(|(i, t)| (t.crop.x0, t.crop.x1, i))
            .collect();
        spans.sort_unstable();
        // Left to right: what lies between the covered reach and the next span is uncovered; a span
        // that starts before the reach overlaps the span that reached there.
        let (mut reach, mut reacher) = (0, usize::MAX);
        for (x0, x1, t) in spans.into_iter().chain([(width, width, usize::MAX)]) {
            if x0 > reach {
                let (count, region, _) = gap.get_or_insert((0, Crop { x0: reach, y0, x1: x0, y1 }, (reach, y0)));
                *count += (x0 - reach) as u64 * (y1 - y0) as u64;
                (region.x0, region.y0) = (region.x0.min(reach), region.y0.min(y0));
                (region.x1, region.y1) = (region.x1.max(x0), region.y1.max(y1));
            } else if x0 < reach && overlap.is_none() {
                overlap = Some((t.max(reacher), t.min(reacher), x0, y0));
            }
            if x1 > reach {
                (reach, reacher) = (x1, t);
            }
        }
    }
    (gap, overlap)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tile(name: &str, crop: Crop) -> Tile {
        let pixels = (0..crop.pixels()).map(|i| Vec3::splat(i as f32)).collect();
        Tile { name: name.into(), width: 5, height: 3, crop, pixels }
    }

    #[test]
    fn crops_parse_and_refuse_bad_input() {
        assert_eq!("1,2,3,4".parse::<Crop>(), Ok(Crop { x0: 1, y0: 2, x1: 3, y1: 4 }));
        for bad in ["1,2,3", "1,2,3,4,5", "a,b,c,d", "-1,0,2,2", ""] {
            assert!(matches!(bad.parse::<Crop>(), Err(TileError::Syntax { .. })), "{bad}");
        }
        assert!(matches!("3,0,3,4".parse::<Crop>(), Err(TileError::Empty { .. })));
        assert!(matches!("0,4,3,2".parse::<Crop>(), Err(TileError::Empty { .. })));
        let crop: Crop = "2,0,6,3".parse().unwrap();
        assert!(matches!(crop.check(5, 3), Err(TileError::Outside { .. })));
        assert_eq!(crop.clipped(5, 3), Crop { x0: 2, y0: 0, x1: 5, y1: 3 });
        assert_eq!(crop.clipped(1, 3).pixels(), 0);
    }

    #[test]
    fn merge_places_tiles_and_names_gaps_and_overlaps() {
        let (a, b) = (Crop { x0: 0, y0: 0, x1: 2, y1: 3 }, Crop { x0: 2, y0: 0, x1: 5, y1: 3 });
        let (w, h, px) = merge_tiles(&[tile("b", b), tile("a", a)]).unwrap();
        assert_eq!((w, h), (5, 3));
        // Pixel (3, 1) is b's pixel (1, 1), index 4 of its 3-wide rows.
        assert_eq!(px[5 + 3], Vec3::splat(4.0));
        assert_eq!(px[5 + 1], Vec3::splat(3.0));

        let err = merge_tiles(&[tile("a", a), tile("a2", Crop { x0: 1, y0: 2, x1: 3, y1: 3 })]).unwrap_err();
        assert_eq!(err, TileError::Overlap { tile: "a2".into(), other: "a".into(), x: 1, y: 2 });
        let err = merge_tiles(&[tile("a", a), tile("b", Crop { x0: 2, y0: 0, x1: 5, y1: 2 })]).unwrap_err();
        let region = Crop { x0: 2, y0: 2, x1: 5, y1: 3 };
        assert_eq!(err, TileError::Gap { count: 3, width: 5, height: 3, region, x: 2, y: 2 });
        let mut other = tile("c", b);
        other.width = 6;
        assert!(matches!(merge_tiles(&[tile("a", a), other]), Err(TileError::ImageSize { .. })));
        assert!(err.to_string().contains("3 pixels"), "{err}");
    }

    #[test]
    fn a_small_tile_claiming_the_largest_image_is_refused_for_its_gap() {
        // The fuzzed case: a 758-byte tile of a 16384-wide image made the merge allocate 2.9 GB
        // before it found the gap. The gap is now found from the crops alone.
        let crop = Crop { x0: 100, y0: 7, x1: 102, y1: 8 };
        let small = Tile { name: "small".into(), width: MAX_SIDE, height: MAX_SIDE, crop, pixels: vec![Vec3::ONE; 2] };
        let err = merge_tiles(&[small]).unwrap_err();
        let region = Crop::full(MAX_SIDE, MAX_SIDE);
        let count = MAX_SIDE as u64 * MAX_SIDE as u64 - 2;
        assert_eq!(err, TileError::Gap { count, width: MAX_SIDE, height: MAX_SIDE, region, x: 0, y: 0 });
    }

    #[test]
    fn gaps_swept_by_bands_match_a_pixel_by_pixel_map() {
        // Every tiling of a 5x3 image by the grids below, with each subset of one or two tiles left
        // out, against an independent per-pixel cover map.
        let (w, h) = (5u32, 3u32);
        for (xs, ys) in [(vec![0, 2, 5], vec![0, 1, 3]), (vec![0, 1, 4, 5], vec![0, 3]), (vec![0, 5], vec![0, 2, 3])] {
            let crops: Vec<Crop> = ys
                .windows(2)
                .flat_map(|y| xs.windows(2).map(move |x| Crop { x0: x[0], y0: y[0], x1: x[1], y1: y[1] }))
                .collect();
            for drop in 0..(1usize << crops.len()) {
                if drop.count_ones() > 2 {
                    continue;
                }
                let kept: Vec<Tile> = (0..crops.len())
                    .filter(|i| drop & (1 << i) == 0)
                    .map(|i| Tile { name: format!("t{i}"), width: w, height: h, crop: crops[i], pixels: vec![] })
                    .collect();
                let uncovered: Vec<(u32, u32)> = (0..h)
                    .flat_map(|y| (0..w).map(move |x| (x, y)))
                    .filter(|&(x, y)| {
                        !kept.iter().any(|t| (t.crop.x0..t.crop.x1).contains(&x) && (t.crop.y0..t.crop.y1).contains(&y))
                    })
                    .collect();
                let expected = uncovered.first().map(|&first| {
                    let b = uncovered.iter().fold(Crop { x0: w, y0: h, x1: 0, y1: 0 }, |b, &(x, y)| Crop {
                        x0: b.x0.min(x),
                        y0: b.y0.min(y),
                        x1: b.x1.max(x + 1),
                        y1: b.y1.max(y + 1),
                    });
                    (uncovered.len() as u64, b, first)
                });
                assert_eq!(cover(&kept, w, h), (expected, None), "grid {xs:?} x {ys:?} without {drop:b}");
                // One more tile over part of the image: its first doubly covered pixel, by the same map.
                let mut over = kept.clone();
                let extra = Crop { x0: 1, y0: 1, x1: 4, y1: 3 };
                over.push(Tile { name: "extra".into(), width: w, height: h, crop: extra, pixels: vec![] });
                let covers = |t: &Tile, (x, y): (u32, u32)| {
                    (t.crop.x0..t.crop.x1).contains(&x) && (t.crop.y0..t.crop.y1).contains(&y)
                };
                let twice = (0..h)
                    .flat_map(|y| (0..w).map(move |x| (x, y)))
                    .find(|&p| over.iter().filter(|t| covers(t, p)).count() > 1);
                let found = cover(&over, w, h).1;
                assert_eq!(found.map(|(_, _, x, y)| (x, y)), twice, "grid {xs:?} x {ys:?} without {drop:b}");
                if let Some((t, other, x, y)) = found {
                    assert!(t > other && covers(&over[t], (x, y)) && covers(&over[other], (x, y)));
                }
            }
        }
    }
}
