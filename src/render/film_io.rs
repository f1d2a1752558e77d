//! Images out: the film as linear OpenEXR (exact), Radiance HDR, or tone-mapped 8-bit sRGB PNG.
//!
//! Pixels are linear sRGB (Rec. 709 primaries), row-major, row 0 at the top, `width * height` of them.
//! - EXR: 32-bit float R, G, B, ZIP (lossless) compression; values are written unchanged, non-finite ones
//!   included, so a broken render can be inspected. Reading the file back gives the same bits.
//! - HDR: Radiance RGBE (8-bit shared exponent, about 1% precision); negative and NaN values become 0.
//! - PNG: `exposure` stops (scale 2^exposure), then Reinhard's operator on luminance (Reinhard et al. 2002,
//!   "Photographic Tone Reproduction for Digital Images", eq. 3: L_d = L / (1 + L), applied as a common scale to
//!   R, G and B so hue is kept), channels clipped to [0, 1], then the sRGB transfer function (IEC 61966-2-1).
//!
//! Files are encoded in memory, written to a temporary file beside the target and renamed onto it, so
//! an error (or a killed process) never leaves a partial file under the target's name.
//!
//! A tile of a larger image (`kelvin render --crop`) is an EXR whose display window is the full
//! image and whose data window is the tile ([`write_exr_tile`], [`read_exr_tile`]). Every EXR
//! records what made it in a `kelvin` text attribute (JSON) ([`crate::provenance`], [`read_exr_provenance`]).

use std::io::Cursor;
use std::path::Path;

use glam::Vec3;

use super::tiles::{Crop, Tile};
use crate::provenance::{ATTRIBUTE, Provenance};
use crate::scene::image::LUMINANCE_WEIGHTS;
use crate::spectrum::color::srgb_encode;

/// What [`write_image`] accepts, for error messages.
pub const WRITE_FORMATS: &str = ".exr (linear f32), .hdr (linear RGBE), .png (tone-mapped 8-bit sRGB)";

/// Why an image could not be written or read back. `what` names the file.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum ImageIoError {
    /// [`write_image`] was given a path whose extension is not one of [`WRITE_FORMATS`].
    #[error("{what}: unknown image extension {given:?}; accepted: {WRITE_FORMATS}")]
    UnknownExtension {
        /// The file.
        what: String,
        /// The extension, lower-cased (empty if none).
        given: String,
    },
    /// The pixel count is not `width * height`.
    #[error("{what}: {len} pixels given for a {width} x {height} image")]
    SizeMismatch {
        /// The file.
        what: String,
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
        /// Number of pixels given.
        len: usize,
    },
    /// A side is zero or larger than the format can store.
    #[error("{what}: cannot write a {width} x {height} image (zero or too large a size)")]
    BadSize {
        /// The file.
        what: String,
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
    },
    /// The encoder failed, or (EXR tiles) the tile is not inside its full image.
    #[error("{what}: {format} encoding failed: {msg}")]
    Encode {
        /// The file.
        what: String,
        /// `"OpenEXR"`, `"PNG"` or `"Radiance HDR"`.
        format: &'static str,
        /// The encoder's message.
        msg: String,
    },
    /// Writing the temporary file or renaming it onto the target failed.
    #[error("{what}: cannot write: {msg}")]
    Io {
        /// The file.
        what: String,
        /// The operating system's message.
        msg: String,
        /// Its kind (a full disk, a permission): whether another machine could do better.
        kind: std::io::ErrorKind,
    },
    /// An EXR could not be read or decoded, or its windows do not describe a tile of an image.
    #[error("{what}: cannot read: {msg}")]
    Read {
        /// The file.
        what: String,
        /// What went wrong.
        msg: String,
    },
}

/// Exposure (stops) that maps the log-average luminance to 18% grey, over the pixels with a finite,
/// positive luminance (an infinite or NaN pixel would set it to -inf or NaN).
pub fn auto_exposure(rgb: &[Vec3]) -> f32 {
    let ys: Vec<f64> =
        rgb.iter().map(|c| c.dot(LUMINANCE_WEIGHTS) as f64).filter(|y| *y > 0.0 && y.is_finite()).collect();
    if ys.is_empty() {
        return 0.0;
    }
    let log_mean = ys.iter().map(|y| y.ln()).sum::<f64>() / ys.len() as f64;
    (0.18f64 / log_mean.exp()).log2() as f32
}

/// Writes linear RGB as a 32-bit float OpenEXR with lossless (ZIP) compression, recording
/// kelvin's version and the program that wrote it ([`Provenance::of_program`]).
pub fn write_exr(path: &Path, width: usize, height: usize, rgb: &[Vec3]) -> Result<(), ImageIoError> {
    write_exr_with(path, width, height, rgb, &Provenance::of_program())
}

/// [`write_exr`] recording `provenance` (the text attribute `kelvin`, a JSON object).
pub fn write_exr_with(
    path: &Path,
    width: usize,
    height: usize,
    rgb: &[Vec3],
    provenance: &Provenance,
) -> Result<(), ImageIoError> {
    let what = path.display().to_string();
    check_dimensions(&what, width, height, rgb, usize::MAX)?;
    let bytes = encode_exr(width, height, rgb, None, provenance).map_err(|msg| ImageIoError::Encode {
        what: what.clone(),
        format: "OpenEXR",
        msg,
    })?;
    write_file(path, &what, &bytes)
}

/// Writes a tile of a `full_width` x `full_height` image: the pixels of `crop` (row-major, its
/// size) as an EXR whose data window is `crop` and whose display window is the full image, with
/// `provenance` (see [`write_exr_with`]).
pub fn write_exr_tile(
    path: &Path,
    crop: Crop,
    full_width: u32,
    full_height: u32,
    rgb: &[Vec3],
    provenance: &Provenance,
) -> Result<(), ImageIoError> {
    let what = path.display().to_string();
    let (width, height) = (crop.width() as usize, crop.height() as usize);
    check_dimensions(&what, width, height, rgb, i32::MAX as usize)?;
    if crop.check(full_width, full_height).is_err() {
        let msg = format!("tile {crop} is not inside the {full_width}x{full_height} image");
        return Err(ImageIoError::Encode { what, format: "OpenEXR", msg });
    }
    let bytes = encode_exr(width, height, rgb, Some((crop, full_width, full_height)), provenance)
        .map_err(|msg| ImageIoError::Encode { what: what.clone(), format: "OpenEXR", msg })?;
    write_file(path, &what, &bytes)
}

/// Reads an EXR as a tile of its display window: the tile's region (the data window) and the full
/// image's size. An EXR of a whole image reads as a tile that covers it.
pub fn read_exr_tile(path: &Path) -> Result<Tile, ImageIoError> {
    let what = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| ImageIoError::Read { what: what.clone(), msg: e.to_string() })?;
    read_exr_tile_from_bytes(&bytes, &what)
}

/// [`read_exr_tile`] and [`read_exr_provenance`] of one read of the file.
pub fn read_exr_tile_and_provenance(path: &Path) -> Result<(Tile, Provenance), ImageIoError> {
    let what = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| ImageIoError::Read { what: what.clone(), msg: e.to_string() })?;
    Ok((read_exr_tile_from_bytes(&bytes, &what)?, read_exr_provenance_from_bytes(&bytes, &what)?))
}

/// [`read_exr_tile`] of a file's bytes; `what` names it in errors.
pub fn read_exr_tile_from_bytes(bytes: &[u8], what: &str) -> Result<Tile, ImageIoError> {
    let (image, pixels) = read_exr_image(bytes, what)?;
    let (w, h) = (image.layer_data.size.width(), image.layer_data.size.height());
    let display = image.attributes.display_window;
    let position = image.layer_data.attributes.layer_position;
    let bad = |msg: String| ImageIoError::Read { what: what.to_owned(), msg };
    if display.position.x() != 0 || display.position.y() != 0 {
        return Err(bad(format!("display window starts at {:?}, not at 0,0", display.position)));
    }
    let (x0, y0) = (u32::try_from(position.x()), u32::try_from(position.y()));
    let (Ok(x0), Ok(y0)) = (x0, y0) else {
        return Err(bad(format!("data window starts at {position:?}, left of or above the image")));
    };
    let end = |start: u32, len: usize| u32::try_from(len).ok().and_then(|l| start.checked_add(l));
    let (Some(x1), Some(y1)) = (end(x0, w), end(y0, h)) else {
        return Err(bad(format!("data window of {w}x{h} at {position:?} ends past 2^32")));
    };
    let (Ok(width), Ok(height)) = (u32::try_from(display.size.width()), u32::try_from(display.size.height())) else {
        return Err(bad(format!("display window of {:?} is too large", display.size)));
    };
    Ok(Tile { name: what.to_owned(), width, height, crop: Crop { x0, y0, x1, y1 }, pixels })
}

/// The provenance an EXR records (its `kelvin` text attribute; empty for a file from elsewhere),
/// read from the header alone.
pub fn read_exr_provenance(path: &Path) -> Result<Provenance, ImageIoError> {
    let what = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| ImageIoError::Read { what: what.clone(), msg: e.to_string() })?;
    read_exr_provenance_from_bytes(&bytes, &what)
}

/// [`read_exr_provenance`] of a file's bytes; `what` names it in errors.
pub fn read_exr_provenance_from_bytes(bytes: &[u8], what: &str) -> Result<Provenance, ImageIoError> {
    use exr::meta::attribute::AttributeValue;
    let what = what.to_owned();
    let read = || exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false);
    let meta =
        catch_decoder_panic(read, &what)?.map_err(|e| ImageIoError::Read { what: what.clone(), msg: e.to_string() })?;
    let Some(header) = meta.headers.first() else { return Ok(Provenance::default()) };
    let attributes = header.shared_attributes.other.iter().chain(&header.own_attributes.other);
    for (name, value) in attributes {
        if let (true, AttributeValue::Text(text)) = (name.eq(ATTRIBUTE), value) {
            let entries = serde_json::from_str(&text.to_string())
                .map_err(|e| ImageIoError::Read { what: what.clone(), msg: format!("attribute {ATTRIBUTE}: {e}") })?;
            return Ok(Provenance(entries));
        }
    }
    Ok(Provenance::default())
}

/// Reads an OpenEXR written by [`write_exr`] back exactly (negative values included, unlike the
/// validating loader for light maps in `scene::image`): width, height and the row-major pixels.
pub fn read_exr(path: &Path) -> Result<(usize, usize, Vec<Vec3>), ImageIoError> {
    let what = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| ImageIoError::Read { what: what.clone(), msg: e.to_string() })?;
    let (image, pixels) = read_exr_image(&bytes, &what)?;
    let size = image.layer_data.size;
    Ok((size.width(), size.height(), pixels))
}

type ExrRgb = exr::image::Image<
    exr::image::Layer<exr::image::SpecificChannels<(usize, Vec<[f32; 3]>), exr::prelude::RgbChannels>>,
>;

/// Most pixels an EXR read back may hold: a 16384 x 16384 image (kelvin's largest).
const MAX_READ_PIXELS: usize = 1 << 28;

/// Runs a decoder call, turning a panic inside it (a malformed file can reach one in the exr
/// crate) into a read error.
fn catch_decoder_panic<R>(f: impl FnOnce() -> R, what: &str) -> Result<R, ImageIoError> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f))
        .map_err(|_| ImageIoError::Read { what: what.to_owned(), msg: "the EXR decoder panicked on this file".into() })
}

/// The first RGB layer of an EXR's bytes, with its attributes (and size), and its row-major pixels.
fn read_exr_image(bytes: &[u8], what: &str) -> Result<(ExrRgb, Vec<Vec3>), ImageIoError> {
    use exr::prelude::{ReadChannels, ReadLayers};
    let what = what.to_owned();
    // The pixels are allocated from the header's size before any is read: refuse what no kelvin
    // image is (a file of a few bytes can claim billions of pixels).
    let meta = catch_decoder_panic(|| exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false), &what)?
        .map_err(|e| ImageIoError::Read { what: what.clone(), msg: e.to_string() })?;
    for h in &meta.headers {
        let (w, ht) = (h.layer_size.width(), h.layer_size.height());
        if w.checked_mul(ht).is_none_or(|n| n > MAX_READ_PIXELS) {
            return Err(ImageIoError::Read { what, msg: format!("{w} x {ht} pixels: larger than kelvin reads") });
        }
    }
    let read = || {
        exr::prelude::read()
            .no_deep_data()
            .largest_resolution_level()
            .rgb_channels(
                // Zeroed arrays of f32 come from the allocator as untouched pages, so that a file whose
                // chunks turn out missing has cost address space, not memory (a 758-byte tile claiming
                // 16384 x 16384 pixels reached 2.9 GB of memory as `Vec3`s).
                |size, _| (size.width(), vec![[0.0f32; 3]; size.width() * size.height()]),
                |(w, px): &mut (usize, Vec<[f32; 3]>), pos, (r, g, b): (f32, f32, f32)| {
                    px[pos.y() * *w + pos.x()] = [r, g, b]
                },
            )
            .first_valid_layer()
            .all_attributes()
            .non_parallel()
            .from_buffered(Cursor::new(bytes))
    };
    let mut image =
        catch_decoder_panic(read, &what)?.map_err(|e| ImageIoError::Read { what: what.clone(), msg: e.to_string() })?;
    let pixels = std::mem::take(&mut image.layer_data.channel_data.pixels.1);
    // Same size and alignment: collected in place, without a copy of the image.
    Ok((image, pixels.into_iter().map(Vec3::from).collect()))
}

/// Writes a tone-mapped 8-bit sRGB PNG; `exposure` is in stops (0 = unchanged). See the module docs.
pub fn write_png(path: &Path, width: usize, height: usize, rgb: &[Vec3], exposure: f32) -> Result<(), ImageIoError> {
    write_png_with(path, width, height, rgb, exposure, None)
}

/// [`write_png`] recording `provenance` in a `tEXt` chunk whose keyword is [`ATTRIBUTE`] (the
/// same JSON object an EXR's attribute holds), in the one file: no sidecar to fall out of step.
pub fn write_png_with(
    path: &Path,
    width: usize,
    height: usize,
    rgb: &[Vec3],
    exposure: f32,
    provenance: Option<&Provenance>,
) -> Result<(), ImageIoError> {
    use image::ImageEncoder;
    let what = path.display().to_string();
    check_dimensions(&what, width, height, rgb, u32::MAX as usize)?;
    let scale = exposure.exp2();
    let data: Vec<u8> = rgb.iter().flat_map(|&c| tone_map_srgb8(c, scale)).collect();
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(&data, width as u32, height as u32, image::ExtendedColorType::Rgb8)
        .map_err(|e| ImageIoError::Encode { what: what.clone(), format: "PNG", msg: e.to_string() })?;
    if let Some(p) = provenance {
        let json = serde_json::to_string(&p.0).map_err(|e| ImageIoError::Encode {
            what: what.clone(),
            format: "PNG",
            msg: e.to_string(),
        })?;
        bytes = super::png_text::with_text(&bytes, ATTRIBUTE, &json);
    }
    write_file(path, &what, &bytes)
}

/// The provenance a PNG written by [`write_png_with`] records (an empty one if it records none).
pub fn read_png_provenance(path: &Path) -> Result<Provenance, ImageIoError> {
    let what = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| ImageIoError::Read { what: what.clone(), msg: e.to_string() })?;
    let bad = |msg: String| ImageIoError::Read { what: what.clone(), msg };
    match super::png_text::text(&bytes, ATTRIBUTE).map_err(bad)? {
        Some(json) => {
            Ok(Provenance(serde_json::from_str(&json).map_err(|e| bad(format!("its {ATTRIBUTE} text: {e}")))?))
        }
        None => Ok(Provenance::default()),
    }
}

/// Writes a Radiance RGBE (.hdr) file; negative and NaN values are written as 0.
pub fn write_hdr(path: &Path, width: usize, height: usize, rgb: &[Vec3]) -> Result<(), ImageIoError> {
    let what = path.display().to_string();
    check_dimensions(&what, width, height, rgb, usize::MAX)?;
    let clean = |v: f32| if v.is_nan() { 0.0 } else { v.clamp(0.0, f32::MAX) };
    let pixels: Vec<image::Rgb<f32>> = rgb.iter().map(|c| image::Rgb([clean(c.x), clean(c.y), clean(c.z)])).collect();
    let mut bytes = Vec::new();
    image::codecs::hdr::HdrEncoder::new(&mut bytes)
        .encode(&pixels, width, height)
        .map_err(|e| ImageIoError::Encode { what: what.clone(), format: "Radiance HDR", msg: e.to_string() })?;
    write_file(path, &what, &bytes)
}

/// Writes by extension: .exr, .hdr or .png (`exposure`, in stops, is used by PNG only).
pub fn write_image(path: &Path, width: usize, height: usize, rgb: &[Vec3], exposure: f32) -> Result<(), ImageIoError> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    match ext.as_str() {
        "exr" => write_exr(path, width, height, rgb),
        "hdr" => write_hdr(path, width, height, rgb),
        "png" => write_png(path, width, height, rgb, exposure),
        _ => Err(ImageIoError::UnknownExtension { what: path.display().to_string(), given: ext }),
    }
}

/// One linear pixel to 8-bit sRGB: scale by `exposure_scale`, Reinhard on luminance, clip, sRGB OETF.
/// NaN must not reach here (debug builds assert); it and negative values give 0.
pub fn tone_map_srgb8(linear: Vec3, exposure_scale: f32) -> [u8; 3] {
    debug_assert!(!linear.is_nan(), "NaN pixel {linear} reached the PNG writer");
    let c = Vec3::from_array(linear.to_array().map(|v| if v.is_nan() { 0.0 } else { v.max(0.0) })) * exposure_scale;
    let lum = c.dot(LUMINANCE_WEIGHTS);
    // Reinhard et al. 2002 eq. 3 on luminance; an infinite luminance maps to white.
    let mapped = if lum.is_finite() { c / (1.0 + lum) } else { Vec3::ONE };
    mapped.to_array().map(|v| (srgb_encode(v as f64) * 255.0).round() as u8)
}

/// `tile`: the crop these pixels are of a full image of the given size (the data and display windows).
fn encode_exr(
    width: usize,
    height: usize,
    rgb: &[Vec3],
    tile: Option<(Crop, u32, u32)>,
    provenance: &Provenance,
) -> Result<Vec<u8>, String> {
    use exr::meta::attribute::{AttributeValue, Text};
    use exr::prelude::{Encoding, Image, IntegerBounds, SpecificChannels, WritableImage};
    let channels = SpecificChannels::rgb(|exr::math::Vec2(x, y): exr::math::Vec2<usize>| {
        let p = rgb[y * width + x];
        (p.x, p.y, p.z)
    });
    let mut image = Image::from_encoded_channels((width, height), Encoding::SMALL_LOSSLESS, channels);
    if let Some((crop, full_width, full_height)) = tile {
        image.attributes.display_window = IntegerBounds::new((0, 0), (full_width as usize, full_height as usize));
        image.layer_data.attributes.layer_position = exr::math::Vec2(crop.x0 as i32, crop.y0 as i32);
    }
    // One attribute holding a JSON object with sorted keys: the crate writes attributes in hash
    // order, so several would make the file's bytes differ from run to run.
    let json = serde_json::to_string(&provenance.0).map_err(|e| e.to_string())?;
    // EXR text is 8-bit: other characters go in as JSON's \u escapes.
    let mut ascii = String::with_capacity(json.len());
    for c in json.chars() {
        if c.is_ascii() {
            ascii.push(c);
        } else {
            c.encode_utf16(&mut [0; 2]).iter().for_each(|u| ascii += &format!("\\u{u:04x}"));
        }
    }
    let text = Text::new_or_none(ascii).ok_or("provenance is not 8-bit text")?;
    image.attributes.other.insert(Text::new_or_panic(ATTRIBUTE), AttributeValue::Text(text));
    let mut bytes = Vec::new();
    image.write().to_buffered(Cursor::new(&mut bytes)).map_err(|e| e.to_string())?;
    Ok(bytes)
}

fn check_dimensions(
    what: &str,
    width: usize,
    height: usize,
    rgb: &[Vec3],
    max_side: usize,
) -> Result<(), ImageIoError> {
    if width == 0 || height == 0 || width > max_side || height > max_side {
        return Err(ImageIoError::BadSize { what: what.into(), width, height });
    }
    if width.checked_mul(height) != Some(rgb.len()) {
        return Err(ImageIoError::SizeMismatch { what: what.into(), width, height, len: rgb.len() });
    }
    Ok(())
}

/// Writes `bytes` durably: to a temporary file beside `path`, flushed to the disk (`fsync`), then
/// renamed onto `path` and the folder flushed, so that after a crash `path` is either absent, the
/// old file or the whole new one, never empty or cut short. `what` names the file in the error.
pub fn write_file(path: &Path, what: &str, bytes: &[u8]) -> Result<(), ImageIoError> {
    use std::io::Write;
    let io = |e: std::io::Error| ImageIoError::Io { what: what.into(), msg: e.to_string(), kind: e.kind() };
    // A temporary name in the same directory, so the rename stays on one file system; unique to this
    // host, process and call, so that writers on storage shared between machines never share one.
    let temp = super::partial::temporary_path(path);
    let written = std::fs::File::create(&temp).and_then(|mut f| {
        f.write_all(bytes)?;
        f.sync_all()
    });
    let renamed = written.and_then(|()| std::fs::rename(&temp, path));
    if let Err(e) = renamed {
        std::fs::remove_file(&temp).ok();
        return Err(io(e));
    }
    // The rename is durable once the folder's entry is (a no-op where folders cannot be opened).
    let folder = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if let Ok(dir) = std::fs::File::open(folder) {
        dir.sync_all().ok();
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tone_map_fixed_points() {
        assert_eq!(tone_map_srgb8(Vec3::ZERO, 1.0), [0, 0, 0]);
        // Luminance 1 maps to 0.5 linear grey, sRGB 188 (0.7354 * 255).
        assert_eq!(tone_map_srgb8(Vec3::ONE, 1.0), [188, 188, 188]);
        assert_eq!(tone_map_srgb8(Vec3::splat(f32::INFINITY), 1.0), [255, 255, 255]);
        assert_eq!(tone_map_srgb8(Vec3::new(-1.0, 0.0, 0.0), 1.0), [0, 0, 0]);
    }

    /// Two writers of one output at once (as two hosts sharing a folder, whose process ids may be
    /// equal) each publish a whole file: neither renames the other's half-written temporary.
    #[test]
    fn concurrent_writers_of_one_output_each_publish_a_whole_file() {
        let dir = std::env::temp_dir().join(format!("kelvin-write-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("out.bin");
        let contents = [vec![1u8; 1 << 16], vec![2u8; 1 << 16]];
        for _ in 0..50 {
            std::thread::scope(|s| {
                for bytes in &contents {
                    let path = &path;
                    s.spawn(move || write_file(path, "out.bin", bytes).unwrap());
                }
            });
            assert!(contents.contains(&std::fs::read(&path).unwrap()), "a whole file of one writer");
        }
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1, "no temporary left");
        std::fs::remove_dir_all(&dir).ok();
    }

    /// A firefly of infinite or NaN radiance does not take the exposure to -inf (a black PNG):
    /// the other pixels set it, as if it were absent.
    #[test]
    fn auto_exposure_skips_non_finite_pixels() {
        let grey = vec![Vec3::splat(0.045); 8];
        let stops = auto_exposure(&grey);
        assert!((stops - 2.0).abs() < 1e-4, "{stops}");
        for bad in [f32::INFINITY, f32::NAN] {
            let mut image = grey.clone();
            image[3] = Vec3::splat(bad);
            assert_eq!(auto_exposure(&image), stops, "{bad}");
        }
        assert_eq!(auto_exposure(&[Vec3::splat(f32::INFINITY)]), 0.0);
    }
}
