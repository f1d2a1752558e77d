//! OpenEXR decoding: the `exr` crate reads the headers and decompresses blocks; kelvin picks the
//! colour channels and places the blocks. Blocks are decompressed and converted to RGB in
//! parallel on rayon's pool, batch by batch, and copied into the image in order. A panic in the
//! crate's decompression reaches the caller (and `load_image_from_bytes`' catch_unwind), where
//! one in the crate's own thread pool would abort the process (found by fuzzing a B44 block).

use std::io::Cursor;

use exr::block::UncompressedBlock;
use exr::block::reader::ChunksReader;
use exr::meta::attribute::{ChannelList, SampleType};
use exr::meta::header::Header;
use glam::Vec3;
use rayon::prelude::*;

use super::image::{ImageError, ImageFormat, RgbImage, check_plausible, check_size};

/// One decompressed block as RGB: its place and size in the layer, rows top to bottom.
struct Block {
    x: usize,
    y: usize,
    width: usize,
    rgb: Vec<Vec3>,
}

/// The image of the first layer with R, G and B (else the first with Y, as grey), at its largest
/// resolution level. Subsampled channels and deep data are errors.
pub(super) fn decode_exr(bytes: &[u8], what: &str) -> Result<RgbImage, ImageError> {
    let decode_error =
        |e: exr::error::Error| ImageError::Decode { what: what.into(), format: "OpenEXR", msg: e.to_string() };
    let unsupported = |msg: String| ImageError::Unsupported { what: what.into(), msg };

    let reader = exr::block::read(Cursor::new(bytes), false).map_err(decode_error)?;
    let mut claimed = 0usize;
    for header in reader.headers() {
        check_size(header.layer_size.0, header.layer_size.1, what)?;
        claimed = claimed.saturating_add(header.layer_size.0 * header.layer_size.1);
    }
    check_plausible(claimed, bytes.len(), ImageFormat::Exr, what)?;

    let names = |h: &Header| -> Vec<String> { h.channels.list.iter().map(|c| c.name.to_string()).collect() };
    let headers = reader.headers();
    let choice = headers
        .iter()
        .enumerate()
        .find_map(|(l, h)| pick_channels(&names(h), &["R", "G", "B"]).map(|i| (l, i)))
        .or_else(|| headers.iter().enumerate().find_map(|(l, h)| pick_channels(&names(h), &["Y"]).map(|i| (l, i))));
    let Some((layer, wanted)) = choice else {
        let channels = headers.iter().flat_map(names).collect::<Vec<_>>().join(", ");
        return Err(ImageError::NoColorChannels { what: what.into(), channels });
    };
    let header = headers[layer].clone();
    if header.deep {
        return Err(unsupported("deep EXR data is not supported".into()));
    }
    for &i in &wanted {
        let channel = &header.channels.list[i];
        if channel.sampling != exr::math::Vec2(1, 1) {
            return Err(unsupported(format!(
                "EXR channel {} is subsampled ({:?}); not supported",
                channel.name, channel.sampling
            )));
        }
    }
    let (width, height) = (header.layer_size.0, header.layer_size.1);

    let chunks = reader
        .filter_chunks(false, |_, tile, block| block.layer == layer && tile.level_index == exr::math::Vec2(0, 0))
        .map_err(decode_error)?;
    let meta = chunks.meta_data().clone();
    let chunks: Vec<_> = chunks.collect::<Result<_, _>>().map_err(decode_error)?;
    let mut pixels = vec![Vec3::ZERO; width * height];
    // In batches, so at most a batch of decoded blocks is held beside the image.
    let batch = 64 * rayon::current_num_threads();
    let mut chunks = chunks.into_iter().peekable();
    while chunks.peek().is_some() {
        let some: Vec<_> = chunks.by_ref().take(batch).collect();
        let blocks: Vec<Block> = some
            .into_par_iter()
            .map(|chunk| {
                let block = UncompressedBlock::decompress_chunk(chunk, &meta, false).map_err(decode_error)?;
                to_rgb(&block, &header.channels, &wanted)
                    .ok_or_else(|| unsupported("a block's lines do not fit it".into()))
            })
            .collect::<Result<_, _>>()?;
        for b in blocks {
            let rows = b.rgb.len() / b.width.max(1);
            if b.x + b.width > width || b.y + rows > height {
                return Err(unsupported(format!(
                    "a block at ({}, {}) reaches outside the {width} x {height} image",
                    b.x, b.y
                )));
            }
            for (r, row) in b.rgb.chunks_exact(b.width).enumerate() {
                let start = (b.y + r) * width + b.x;
                pixels[start..start + b.width].copy_from_slice(row);
            }
        }
    }
    Ok(RgbImage { width, height, pixels })
}

/// The wanted channels of `block` (three: R, G, B; one: grey) as RGB; None when a line does not
/// fit the block (a malformed file).
fn to_rgb(block: &UncompressedBlock, channels: &ChannelList, wanted: &[usize]) -> Option<Block> {
    let (x0, y0) = (block.index.pixel_position.0, block.index.pixel_position.1);
    let (w, h) = (block.index.pixel_size.0, block.index.pixel_size.1);
    let mut rgb = vec![Vec3::ZERO; w * h];
    for line in block.lines(channels) {
        let Some(k) = wanted.iter().position(|&i| i == line.location.channel) else { continue };
        let row = line.location.position.1.checked_sub(y0)?;
        let out = rgb.get_mut(row * w..(row + 1) * w)?;
        let sample_type = channels.list[line.location.channel].sample_type;
        let size = match sample_type {
            SampleType::F16 => 2,
            SampleType::F32 | SampleType::U32 => 4,
        };
        if line.value.len() != w * size {
            return None;
        }
        for (p, b) in out.iter_mut().zip(line.value.chunks_exact(size)) {
            p[k] = match sample_type {
                SampleType::F16 => exr::prelude::f16::from_ne_bytes([b[0], b[1]]).to_f32(),
                SampleType::F32 => f32::from_ne_bytes([b[0], b[1], b[2], b[3]]),
                SampleType::U32 => u32::from_ne_bytes([b[0], b[1], b[2], b[3]]) as f32,
            };
        }
    }
    if wanted.len() == 1 {
        rgb.iter_mut().for_each(|p| *p = Vec3::splat(p.x));
    }
    Some(Block { x: x0, y: y0, width: w, rgb })
}

/// Indices of the wanted channels (e.g. R, G, B) among `names`, all from one channel-name layer: the unprefixed
/// ones ("R") first, then the alphabetically first prefix ("diffuse.R"). Channel names compare case-insensitively.
fn pick_channels(names: &[String], wanted: &[&str]) -> Option<Vec<usize>> {
    let split = |name: &str| match name.rsplit_once('.') {
        Some((prefix, base)) => (prefix.to_string(), base.to_ascii_uppercase()),
        None => (String::new(), name.to_ascii_uppercase()),
    };
    let mut prefixes: Vec<String> = names.iter().map(|n| split(n).0).collect();
    prefixes.sort();
    prefixes.dedup(); // "" sorts first
    prefixes.iter().find_map(|prefix| {
        wanted
            .iter()
            .map(|w| names.iter().position(|n| split(n) == (prefix.clone(), w.to_string())))
            .collect::<Option<Vec<usize>>>()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pick_channels_prefers_unprefixed_then_first_prefix() {
        let names: Vec<String> = ["A", "B", "G", "R", "diffuse.B", "diffuse.G", "diffuse.R"].map(String::from).into();
        assert_eq!(pick_channels(&names, &["R", "G", "B"]), Some(vec![3, 2, 1]));
        let names: Vec<String> = ["a.R", "a.G", "b.R", "b.G", "b.B"].map(String::from).into();
        assert_eq!(pick_channels(&names, &["R", "G", "B"]), Some(vec![2, 3, 4]));
        assert_eq!(pick_channels(&names, &["Y"]), None);
    }
}
