//! Images in: OpenEXR, Radiance HDR, PNG and JPEG as linear RGB, for environment maps, light images and glTF
//! textures.
//!
//! # Validation policy
//!
//! Environment maps and light images become sampling distributions and emitted radiance, so bad pixels are not
//! let through silently:
//! - NaN or +/-Inf in any channel: the load fails with [`ImageError::NonFinite`], naming the file, the first bad
//!   pixel (x, y) in row-major order and how many pixels are bad (pbrt-v4 `lights.cpp` likewise refuses light
//!   images with NaN or infinite pixels).
//! - Negative values (only EXR can hold them): clamped to 0, counted, and reported in [`LoadedImage::warnings`]
//!   for the caller to print.
//! - Missing, unreadable, empty (zero-byte), zero-size, truncated or corrupt files and unknown formats each give an
//!   [`ImageError`] naming the file. Images over [`MAX_PIXELS`] pixels are refused before their pixels are decoded,
//!   and so are EXR and HDR files whose header claims more than [`MAX_PIXELS_PER_BYTE`] pixels per byte of file.
//!
//! Loading never panics; a panic inside a third-party decoder is caught and reported as [`ImageError::Decode`].
//!
//! # Colour
//!
//! EXR and HDR pixels are taken as linear. PNG and JPEG (8 or 16 bit) are decoded with the sRGB transfer function
//! (IEC 61966-2-1) whatever gamma or ICC profile they carry; alpha is dropped and grey is replicated to RGB.
//! An EXR's first layer (part) with R, G and B channels is read (or, failing that, its first with a Y channel, as
//! grey); f16, f32 and u32 samples, scan-line or tiled, are all accepted.
//!
//! # Equirectangular (lat-long) maps
//!
//! In kelvin's frame (+Y up, right-handed), for `uv` in \[0,1\]^2 with v = 0 on the top row:
//! - v = 0 is the zenith (+Y), v = 0.5 the horizon, v = 1 the nadir (-Y): polar angle theta = pi v.
//! - u = 0.5 (the image centre) looks along +X, u = 0.75 along +Z, u = 0 and 1 along -X, and u = 0.25 along -Z
//!   (glTF forward: what a default glTF camera sees): azimuth phi = 2 pi (u - 0.5), measured from +X toward +Z.
//!
//! This is the mapping of three.js (`equirectUv`), the Khronos glTF Sample Viewer (`panorama_to_cubemap`) and
//! Blender's environment texture once Blender's Z-up frame is turned to glTF's Y-up one (as its glTF exporter
//! does), so an HDRI shows the same way in kelvin as in those viewers.

use std::f32::consts::{PI, TAU};
use std::io::Cursor;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use glam::{Vec2, Vec3};

use crate::lanes::math::atan2_pos;
use crate::lanes::{F32x16, LANES, Real3, U32x16, Vec3x16, Vector};

/// The largest image accepted, in pixels (2^28, e.g. 23170 x 23170; 3 GiB as linear f32 RGB).
pub const MAX_PIXELS: usize = 1 << 28;

/// The most pixels an EXR or HDR file may claim per byte of file. Decoders allocate the whole image from the
/// header before reading pixel data, so a few hundred bytes claiming 50 million pixels cost gigabytes (found by
/// fuzzing). Real files stay far below: RGBE run-length coding reaches about 16 pixels per byte and zlib about
/// 1000:1 (172 f16 RGB pixels per byte).
pub const MAX_PIXELS_PER_BYTE: usize = 4096;

/// Rec. 709 / sRGB luminance weights: the Y row of the sRGB-to-XYZ matrix (IEC 61966-2-1), as in
/// [`crate::spectrum::color::SRGB_TO_XYZ`].
pub const LUMINANCE_WEIGHTS: Vec3 = Vec3::new(0.2126729, 0.7151522, 0.0721750);

/// What [`load_image`] and [`load_image_from_bytes`] accept, for error messages.
pub const IMAGE_FORMATS: &str = ".exr, .hdr, .png, .jpg / .jpeg (or the MIME types image/png, image/jpeg)";

/// A linear RGB image.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    /// Width in pixels, at least 1.
    pub width: usize,
    /// Height in pixels, at least 1.
    pub height: usize,
    /// `width * height` linear RGB pixels, row-major, row 0 at the top.
    pub pixels: Vec<Vec3>,
}

/// A loaded image with what the validation policy changed (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedImage {
    /// The pixels, all finite and non-negative.
    pub image: RgbImage,
    /// Human-readable notes (e.g. "clamped 12 negative pixels to 0"), each naming the file.
    pub warnings: Vec<String>,
}

/// Why an image could not be loaded. `what` names the file (or the in-memory source).
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum ImageError {
    /// The file does not exist.
    #[error("{what}: file not found")]
    NotFound {
        /// The file.
        what: String,
    },
    /// The file exists but could not be read.
    #[error("{what}: cannot read: {msg}")]
    Io {
        /// The file.
        what: String,
        /// The operating system's message.
        msg: String,
    },
    /// The extension or MIME type is not one of [`IMAGE_FORMATS`].
    #[error("{what}: unknown image format {given:?}; accepted: {IMAGE_FORMATS}")]
    UnknownFormat {
        /// The file or source.
        what: String,
        /// The extension or MIME type given.
        given: String,
    },
    /// The file or buffer has zero bytes.
    #[error("{what}: empty (zero bytes)")]
    Empty {
        /// The file or source.
        what: String,
    },
    /// The data is corrupt or truncated, its header claims implausibly many pixels for its size
    /// ([`MAX_PIXELS_PER_BYTE`]), or the decoder panicked.
    #[error("{what}: corrupt or truncated {format} data: {msg}")]
    Decode {
        /// The file or source.
        what: String,
        /// The format's name ([`ImageFormat::name`]).
        format: &'static str,
        /// The decoder's message.
        msg: String,
    },
    /// The image is 0 pixels wide or high.
    #[error("{what}: image has zero size ({width} x {height})")]
    ZeroSize {
        /// The file or source.
        what: String,
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
    },
    /// The image has more than [`MAX_PIXELS`] pixels.
    #[error("{what}: image too large ({width} x {height} pixels; at most {MAX_PIXELS} pixels accepted)")]
    TooLarge {
        /// The file or source.
        what: String,
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
    },
    /// No EXR layer has R, G and B channels, or a Y channel.
    #[error("{what}: no R, G, B or Y channels in any EXR layer (found: {channels})")]
    NoColorChannels {
        /// The file or source.
        what: String,
        /// The channel names found, comma-separated.
        channels: String,
    },
    /// An image kelvin does not read: subsampled EXR channels, one over the decoder's allocation
    /// limit, or a decoder that gave a pixel count other than width x height.
    #[error("{what}: {msg}")]
    Unsupported {
        /// The file or source.
        what: String,
        /// What is not supported.
        msg: String,
    },
    /// Some pixels have a NaN or infinite channel (see the module's validation policy).
    #[error(
        "{what}: {count} pixel(s) with NaN or infinite values, first at (x {x}, y {y}) = {value}; \
         not usable as a light or environment map"
    )]
    NonFinite {
        /// The file or source.
        what: String,
        /// Column of the first bad pixel (row-major order).
        x: usize,
        /// Row of the first bad pixel, from the top.
        y: usize,
        /// The first bad pixel's value, as text.
        value: String,
        /// Number of bad pixels.
        count: usize,
    },
}

/// The formats kelvin reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// OpenEXR, linear.
    Exr,
    /// Radiance RGBE, linear.
    Hdr,
    /// PNG, sRGB-encoded.
    Png,
    /// JPEG, sRGB-encoded.
    Jpeg,
}

impl ImageFormat {
    /// From a file extension or MIME type, case-insensitive: "exr", ".hdr", "png", "jpg", "jpeg", "image/png", ...
    pub fn from_hint(hint: &str) -> Option<Self> {
        let h = hint.trim().to_ascii_lowercase();
        let h = h.strip_prefix("image/").unwrap_or(&h);
        let h = h.strip_prefix('.').unwrap_or(h);
        match h {
            "exr" | "x-exr" => Some(Self::Exr),
            "hdr" | "vnd.radiance" => Some(Self::Hdr),
            "png" => Some(Self::Png),
            "jpg" | "jpeg" => Some(Self::Jpeg),
            _ => None,
        }
    }

    /// The format's name in messages.
    pub fn name(self) -> &'static str {
        match self {
            Self::Exr => "OpenEXR",
            Self::Hdr => "Radiance HDR",
            Self::Png => "PNG",
            Self::Jpeg => "JPEG",
        }
    }
}

/// `x.floor()`, inline: without SSE4.1 (kelvin's baseline target) `f32::floor` is a call into
/// libm, twice per bilinear lookup. Equal to it for every input (NaN and infinities included; -0.0
/// gives 0.0, which the lookup cannot tell apart).
#[inline]
fn floor(x: f32) -> f32 {
    // Floats of magnitude 2^23 and above are whole numbers; below it the i32 cast is exact.
    if x.abs() < 8_388_608.0 {
        let t = x as i32 as f32;
        if t > x { t - 1.0 } else { t }
    } else {
        x
    }
}

impl RgbImage {
    /// The pixel at column `x`, row `y` (row 0 at the top). Panics if `x >= width` or `y >= height`.
    pub fn get(&self, x: usize, y: usize) -> Vec3 {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside {}x{}", self.width, self.height);
        self.pixels[y * self.width + x]
    }

    /// Luminance (Rec. 709 Y) of pixel (x, y); in cd/m^2 when the image is photometric (see DESIGN.md).
    pub fn luminance(&self, x: usize, y: usize) -> f32 {
        self.get(x, y).dot(LUMINANCE_WEIGHTS)
    }

    /// Bilinear lookup at `uv` in \[0,1\]^2 (v = 0 at the top), pixel centres at ((x + 0.5) / w, (y + 0.5) / h).
    /// u wraps around (the lat-long seam) and v is clamped (the poles). Non-finite `uv` gives a defined pixel,
    /// never a panic.
    pub fn bilinear(&self, uv: Vec2) -> Vec3 {
        debug_assert!(uv.is_finite(), "bilinear lookup at non-finite uv {uv}");
        let (w, h) = (self.width as i64, self.height as i64);
        let fx = uv.x * self.width as f32 - 0.5;
        let fy = uv.y * self.height as f32 - 0.5;
        let (x0, y0) = (floor(fx), floor(fy));
        let (tx, ty) = (fx - x0, fy - y0);
        // Float-to-int casts saturate (NaN -> 0), so any uv gives an index in range after wrap / clamp.
        let row = |j: i64| j.clamp(0, h - 1) as usize;
        let (x0, y0) = (x0 as i64, y0 as i64);
        // One 64-bit remainder, not two: x0 + 1 wraps to column 0 exactly when x0 is the last.
        let c0 = x0.rem_euclid(w) as usize;
        let c1 = if c0 + 1 == self.width { 0 } else { c0 + 1 };
        let (r0, r1) = (row(y0), row(y0.saturating_add(1)));
        let px = |c: usize, r: usize| self.pixels[r * self.width + c];
        let top = px(c0, r0).lerp(px(c1, r0), tx);
        let bottom = px(c0, r1).lerp(px(c1, r1), tx);
        let out = top.lerp(bottom, ty);
        if out.is_finite() { out } else { px(c0, r0) }
    }

    /// [`Self::bilinear`] at a lane each, the same bits, for `u` in [0, 1) and `v` in [0, 1] (as
    /// [`lat_long_of`] gives them); lanes outside that read some pixel of the image.
    #[inline(always)]
    pub fn bilinear_lanes(&self, u: F32x16, v: F32x16) -> Vec3x16 {
        // Pixel counts are at most `MAX_PIXELS` (2^28): indices fit in i32.
        let (w, h) = (self.width as i32, self.height as i32);
        let fx = u * self.width as f32 - 0.5;
        let fy = v * self.height as f32 - 0.5;
        let (mut tx, mut ty) = (F32x16::ZERO, F32x16::ZERO);
        let mut index = [[0u32; LANES]; 4];
        for l in 0..LANES {
            let (x0, y0) = (floor(fx[l]), floor(fy[l]));
            (tx[l], ty[l]) = (fx[l] - x0, fy[l] - y0);
            // x0 is in [-1, w - 1] for u in [0, 1): one wrap, no remainder (which does not vectorise).
            let x = x0 as i32;
            let c0 = (if x < 0 { x + w } else { x }).clamp(0, w - 1);
            let c1 = if c0 + 1 == w { 0 } else { c0 + 1 };
            let y = y0 as i32;
            let (r0, r1) = (y.clamp(0, h - 1) * w, y.saturating_add(1).clamp(0, h - 1) * w);
            index[0][l] = (r0 + c0) as u32;
            index[1][l] = (r0 + c1) as u32;
            index[2][l] = (r1 + c0) as u32;
            index[3][l] = (r1 + c1) as u32;
        }
        let px = |i: usize| Vec3x16::gather(&self.pixels, U32x16(index[i]));
        let (p00, p10, p01, p11) = (px(0), px(1), px(2), px(3));
        // glam's lerp: a (1 - s) + b s.
        let one = F32x16::splat(1.0);
        let top = p00 * (one - tx) + p10 * tx;
        let bottom = p01 * (one - tx) + p11 * tx;
        let out = top * (one - ty) + bottom * ty;
        Vec3x16::select(out.is_finite(), out, p00)
    }

    /// Sum of all pixels' luminance divided by the pixel count (an unweighted mean, not solid-angle weighted).
    pub fn mean_luminance(&self) -> f64 {
        let sum: f64 = self.pixels.iter().map(|p| p.dot(LUMINANCE_WEIGHTS) as f64).sum();
        sum / self.pixels.len().max(1) as f64
    }

    /// The largest pixel luminance.
    pub fn max_luminance(&self) -> f32 {
        self.pixels.iter().map(|p| p.dot(LUMINANCE_WEIGHTS)).fold(0.0, f32::max)
    }
}

/// The sRGB decoding function (IEC 61966-2-1): encoded value in [0, 1] to linear, the inverse of
/// [`crate::spectrum::color::srgb_encode`]. Inputs outside [0, 1] are clamped; NaN gives 0.
pub fn srgb_decode(encoded: f64) -> f64 {
    let c = if encoded.is_nan() { 0.0 } else { encoded.clamp(0.0, 1.0) };
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

/// The direction (unit, +Y up) of a lat-long map at `uv` (v = 0 at the top); see the module docs.
pub fn lat_long_direction(uv: Vec2) -> Vec3 {
    let phi = TAU * (uv.x - 0.5);
    let theta = PI * uv.y;
    let (sin_theta, cos_theta) = theta.sin_cos();
    let (sin_phi, cos_phi) = phi.sin_cos();
    Vec3::new(sin_theta * cos_phi, cos_theta, sin_theta * sin_phi)
}

/// The lat-long `uv` (u in [0, 1), v in [0, 1], v = 0 at the top) of direction `dir`, the inverse of
/// [`lat_long_direction`]. `dir` need not be normalised; at the poles (and for a zero `dir`) u is 0.5.
pub fn direction_to_lat_long(dir: Vec3) -> Vec2 {
    Vec2::from(lat_long_of::<f32>(dir))
}

/// [`direction_to_lat_long`] written once over [`Real3`], for one direction or a lane each (the
/// same bits): atan2 as a polynomial (`lanes::math::atan2_pos`, relative error 4e-7), not libm.
#[inline(always)]
pub fn lat_long_of<F: Real3>(dir: F::Vector) -> [F; 2] {
    let d = dir.normalize_or_zero();
    let [x, y, z] = d.xyz();
    // A zero `dir` stays zero; any other is unit.
    let none = d.dot(d).lt(F::splat(0.5));
    // The polar angle from its sine and cosine keeps its precision near the poles (acos(y) would not).
    let theta = atan2_pos((x * x + z * z).sqrt(), y);
    let phi = atan2_pos(z.abs(), x);
    let phi = F::select(z.lt(F::splat(0.0)), -phi, phi);
    let u = phi / TAU + 0.5;
    // phi = +pi gives u = 1: keep u in [0, 1) so it indexes the first column.
    let u = F::select(u.ge(F::splat(1.0)), u - 1.0, u);
    let half = F::splat(0.5);
    [F::select(none, half, u), F::select(none, half, theta / PI)]
}

/// Loads an image file; the format comes from the extension (see the module docs for the checks made).
pub fn load_image(path: &Path) -> Result<LoadedImage, ImageError> {
    load_image_recorded(path).map(|(image, _)| image)
}

/// [`load_image`], with the record of the bytes it decoded (their SHA-256, hashed as read).
pub fn load_image_recorded(path: &Path) -> Result<(LoadedImage, crate::provenance::InputFile), ImageError> {
    let what = path.display().to_string();
    let ext = path.extension().map(|e| e.to_string_lossy().into_owned()).unwrap_or_default();
    // Check the extension first so a typo in it is reported as such even when the file is missing.
    if ImageFormat::from_hint(&ext).is_none() {
        return Err(ImageError::UnknownFormat { what, given: ext });
    }
    let bytes = std::fs::read(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => ImageError::NotFound { what: what.clone() },
        _ => ImageError::Io { what: what.clone(), msg: e.to_string() },
    })?;
    Ok((load_image_from_bytes(&bytes, &ext, &what)?, crate::provenance::InputFile::read(path, &bytes)))
}

/// Loads an image held in memory (glTF embedded textures, fuzzing). `format_hint` is an extension or MIME type
/// (see [`ImageFormat::from_hint`]); `what` names the source in errors and warnings.
pub fn load_image_from_bytes(bytes: &[u8], format_hint: &str, what: &str) -> Result<LoadedImage, ImageError> {
    let format = ImageFormat::from_hint(format_hint)
        .ok_or_else(|| ImageError::UnknownFormat { what: what.into(), given: format_hint.into() })?;
    if bytes.is_empty() {
        return Err(ImageError::Empty { what: what.into() });
    }
    let decoded = catch_unwind(AssertUnwindSafe(|| match format {
        ImageFormat::Exr => super::exr_decode::decode_exr(bytes, what),
        ImageFormat::Hdr => decode_with_image_crate(bytes, image::ImageFormat::Hdr, format, what),
        ImageFormat::Png => decode_with_image_crate(bytes, image::ImageFormat::Png, format, what),
        ImageFormat::Jpeg => decode_with_image_crate(bytes, image::ImageFormat::Jpeg, format, what),
    }))
    .unwrap_or_else(|_| {
        Err(ImageError::Decode { what: what.into(), format: format.name(), msg: "the decoder panicked".into() })
    })?;
    validate(decoded, what)
}

/// Checks the size, rejects non-finite pixels and clamps negative ones (the module's validation policy).
fn validate(image: RgbImage, what: &str) -> Result<LoadedImage, ImageError> {
    check_size(image.width, image.height, what)?;
    if image.pixels.len() != image.width * image.height {
        return Err(ImageError::Unsupported {
            what: what.into(),
            msg: format!("{} pixels decoded for a {} x {} image", image.pixels.len(), image.width, image.height),
        });
    }
    let mut bad = image.pixels.iter().enumerate().filter(|(_, p)| !p.is_finite());
    if let Some((first, p)) = bad.next() {
        return Err(ImageError::NonFinite {
            what: what.into(),
            x: first % image.width,
            y: first / image.width,
            value: format!("({}, {}, {})", p.x, p.y, p.z),
            count: 1 + bad.count(),
        });
    }
    let mut image = image;
    let mut negative = 0usize;
    for p in &mut image.pixels {
        if p.cmplt(Vec3::ZERO).any() {
            negative += 1;
            *p = p.max(Vec3::ZERO);
        }
    }
    let mut warnings = Vec::new();
    if negative > 0 {
        warnings.push(format!("{what}: clamped {negative} pixel(s) with negative values to 0"));
    }
    Ok(LoadedImage { image, warnings })
}

/// Refuses a header claiming far more pixels than `file_len` bytes can encode (see [`MAX_PIXELS_PER_BYTE`]).
pub(super) fn check_plausible(
    pixels: usize,
    file_len: usize,
    format: ImageFormat,
    what: &str,
) -> Result<(), ImageError> {
    if pixels > file_len.saturating_mul(MAX_PIXELS_PER_BYTE) {
        return Err(ImageError::Decode {
            what: what.into(),
            format: format.name(),
            msg: format!(
                "the header claims {pixels} pixels, more than a {file_len}-byte file can hold \
                 (at most {MAX_PIXELS_PER_BYTE} per byte)"
            ),
        });
    }
    Ok(())
}

pub(super) fn check_size(width: usize, height: usize, what: &str) -> Result<(), ImageError> {
    if width == 0 || height == 0 {
        return Err(ImageError::ZeroSize { what: what.into(), width, height });
    }
    if width.checked_mul(height).is_none_or(|n| n > MAX_PIXELS) {
        return Err(ImageError::TooLarge { what: what.into(), width, height });
    }
    Ok(())
}

/// PNG, JPEG and HDR through the `image` crate, with allocation limits so a hostile header cannot exhaust memory.
fn decode_with_image_crate(
    bytes: &[u8],
    crate_format: image::ImageFormat,
    format: ImageFormat,
    what: &str,
) -> Result<RgbImage, ImageError> {
    let decode_error = |e: image::ImageError| match e {
        image::ImageError::Limits(_) => ImageError::Unsupported {
            what: what.into(),
            msg: format!("image too large to decode ({e}); at most {MAX_PIXELS} pixels accepted"),
        },
        _ => ImageError::Decode { what: what.into(), format: format.name(), msg: e.to_string() },
    };
    let mut reader = image::ImageReader::with_format(Cursor::new(bytes), crate_format);
    let mut limits = image::Limits::default();
    // Four f32 channels per pixel is the largest decoded form.
    limits.max_alloc = Some(MAX_PIXELS as u64 * 16);
    reader.limits(limits.clone());
    let (w, h) = reader.into_dimensions().map_err(decode_error)?;
    check_size(w as usize, h as usize, what)?;
    if format == ImageFormat::Hdr {
        check_plausible(w as usize * h as usize, bytes.len(), format, what)?;
    }
    let mut reader = image::ImageReader::with_format(Cursor::new(bytes), crate_format);
    reader.limits(limits);
    let img = reader.decode().map_err(decode_error)?;
    let (width, height) = (img.width() as usize, img.height() as usize);
    check_size(width, height, what)?;
    let pixels = match format {
        ImageFormat::Hdr => img.into_rgb32f().pixels().map(|p| Vec3::from_array(p.0)).collect(),
        _ if img.color().bytes_per_pixel() / img.color().channel_count() == 1 => {
            let lut: Vec<f32> = (0..=255u8).map(|v| srgb_decode(v as f64 / 255.0) as f32).collect();
            let rgb = img.into_rgb8();
            rgb.pixels().map(|p| Vec3::new(lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize])).collect()
        }
        _ => {
            let decode = |v: u16| srgb_decode(v as f64 / 65535.0) as f32;
            img.into_rgb16().pixels().map(|p| Vec3::new(decode(p[0]), decode(p[1]), decode(p[2]))).collect()
        }
    };
    Ok(RgbImage { width, height, pixels })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectrum::color::srgb_encode;

    #[test]
    fn srgb_decode_inverts_encode() {
        for i in 0..=1000 {
            let x = i as f64 / 1000.0;
            assert!((srgb_decode(srgb_encode(x)) - x).abs() < 1e-12, "x = {x}");
        }
        // 50% grey in 8 bit (128/255) is 21.586% linear (IEC 61966-2-1).
        assert!((srgb_decode(128.0 / 255.0) - 0.2158605).abs() < 1e-6);
    }

    #[test]
    fn format_hints() {
        assert_eq!(ImageFormat::from_hint("image/jpeg"), Some(ImageFormat::Jpeg));
        assert_eq!(ImageFormat::from_hint(".EXR"), Some(ImageFormat::Exr));
        assert_eq!(ImageFormat::from_hint("tiff"), None);
    }

    #[test]
    fn inline_floor_equals_f32_floor() {
        let specials =
            [0.0, -0.0, 0.5, -0.5, 1.0, -1.0, 8_388_607.5, -8_388_607.5, 8_388_608.0, -8_388_609.0, 3e9, -3e9];
        let walk = (-40_000..=40_000).map(|i| i as f32 * 0.37 + 0.01);
        let ulps = (0..2000u32).flat_map(|i| [f32::from_bits(0x3f80_0000 - i), f32::from_bits(0xbf80_0000 - i)]);
        for x in
            specials.into_iter().chain(walk).chain(ulps).chain([f32::INFINITY, f32::NEG_INFINITY, f32::MAX, f32::MIN])
        {
            assert_eq!(floor(x), x.floor(), "{x}");
        }
        assert!(floor(f32::NAN).is_nan());
    }
}
