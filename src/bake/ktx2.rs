//! KTX 2.0 files of packed HDR texels, written from the specification (Khronos KTX File Format
//! Specification 2.0, and the Khronos Data Format Specification 1.3 for the data format
//! descriptor): one mip level of a 2D or 3D texture in `VK_FORMAT_E5B9G9R9_UFLOAT_PACK32` or
//! `VK_FORMAT_B10G11R11_UFLOAT_PACK32`, optionally Zstandard-supercompressed (scheme 2), as Bevy
//! loads lightmaps and irradiance volumes.
//!
//! Layout: the 80-byte header and index, the level index (one entry), the data format descriptor
//! (one basic block), the key/value data (`KTXwriter`), then the level's bytes (little-endian
//! u32 texels, x fastest, then y (row 0 first), then z). No supercompression global data.

use glam::Vec3;

/// The file identifier: «KTX 20»\r\n\x1A\n.
pub const IDENTIFIER: [u8; 12] = [0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A];
/// `supercompressionScheme` of Zstandard.
pub const ZSTD_SCHEME: u32 = 2;

/// A packed unsigned-float texel format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// `VK_FORMAT_E5B9G9R9_UFLOAT_PACK32` (123): 9-bit mantissas, one shared 5-bit exponent.
    E5B9G9R9,
    /// `VK_FORMAT_B10G11R11_UFLOAT_PACK32` (122): 11-bit R and G, 10-bit B unsigned floats.
    B10G11R11,
}

impl Format {
    /// The `VkFormat` value.
    pub fn vk_format(self) -> u32 {
        match self {
            Self::E5B9G9R9 => 123,
            Self::B10G11R11 => 122,
        }
    }

    /// Packs linear RGB (negative and NaN channels become 0, too large ones the largest value).
    pub fn pack(self, rgb: Vec3) -> u32 {
        match self {
            Self::E5B9G9R9 => pack_e5b9g9r9(rgb),
            Self::B10G11R11 => pack_b10g11r11(rgb),
        }
    }

    /// The RGB a packed texel holds.
    pub fn unpack(self, texel: u32) -> Vec3 {
        match self {
            Self::E5B9G9R9 => unpack_e5b9g9r9(texel),
            Self::B10G11R11 => unpack_b10g11r11(texel),
        }
    }

    /// The basic data format descriptor block's samples: (channel and qualifier bits, bit offset,
    /// bit length, sampleLower, sampleUpper), as the Data Format Specification describes the format.
    fn samples(self) -> Vec<(u8, u16, u8, u32, u32)> {
        // Qualifier bits of the channel byte: F(loat) and E(xponent).
        const FLOAT: u8 = 0x80;
        const EXPONENT: u8 = 0x20;
        match self {
            // Per channel a 9-bit mantissa with explicit 1 (1.0 = mantissa 256 with exponent 16:
            // 0x2100) and the shared exponent, bias 15, no infinity or NaN encodings.
            Self::E5B9G9R9 => {
                (0..3u8).flat_map(|c| [(c, 9 * c as u16, 9, 0, 0x2100), (c | EXPONENT, 27, 5, 15, 31)]).collect()
            }
            // Unsigned floats in [0.0, 1.0] terms: sampleLower 0.0f, sampleUpper 1.0f.
            Self::B10G11R11 => {
                let one = 1.0f32.to_bits();
                vec![(FLOAT, 0, 11, 0, one), (1 | FLOAT, 11, 11, 0, one), (2 | FLOAT, 22, 10, 0, one)]
            }
        }
    }
}

/// How the level data is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Supercompression {
    /// As is.
    None,
    /// Zstandard at this level (1 to 22; 0 is zstd's default).
    Zstd(i32),
}

/// Why a texture cannot be encoded.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Ktx2Error {
    /// The texel count is not width x height x max(depth, 1), or a side is 0 (or too large).
    #[error("KTX2: {len} texels given for a {width} x {height} x {depth} texture")]
    Size {
        /// Width, texels.
        width: u32,
        /// Height, texels.
        height: u32,
        /// Depth, texels (0 for a 2D texture).
        depth: u32,
        /// Texels given.
        len: usize,
    },
    /// Zstandard failed.
    #[error("KTX2: zstd supercompression failed: {0}")]
    Zstd(String),
}

/// A texture to write: `width` x `height` texels, times `depth` slices for a 3D texture (0 for 2D).
#[derive(Clone, Copy, Debug)]
pub struct Texture<'a> {
    /// Texel format.
    pub format: Format,
    /// Width, texels (>= 1).
    pub width: u32,
    /// Height, texels (>= 1).
    pub height: u32,
    /// Depth, texels: 0 for a 2D texture, >= 1 for a 3D one.
    pub depth: u32,
    /// Linear RGB, x fastest, then y (row 0 is the top), then z.
    pub texels: &'a [Vec3],
}

/// Little-endian writes.
trait Put {
    fn u32(&mut self, v: u32);
    fn u64(&mut self, v: u64);
}

impl Put for Vec<u8> {
    fn u32(&mut self, v: u32) {
        self.extend_from_slice(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.extend_from_slice(&v.to_le_bytes());
    }
}

/// The data format descriptor: dfdTotalSize, then one basic descriptor block.
fn data_format_descriptor(format: Format) -> Vec<u8> {
    let samples = format.samples();
    let block_size = 24 + 16 * samples.len() as u32;
    let mut d = Vec::with_capacity(4 + block_size as usize);
    d.u32(4 + block_size);
    // vendorId 0 (Khronos), descriptorType 0 (basic).
    d.u32(0);
    // versionNumber 2, descriptorBlockSize.
    d.u32(2 | block_size << 16);
    // colorModel RGBSDA (1), colorPrimaries BT709 (1), transferFunction LINEAR (1), flags 0.
    d.u32(1 | 1 << 8 | 1 << 16);
    // texelBlockDimension0..3: 1x1x1x1 (stored minus one).
    d.u32(0);
    // bytesPlane0 = 4 (one 32-bit texel), planes 1 to 7 empty.
    d.u32(4);
    d.u32(0);
    for (channel, offset, bits, lower, upper) in samples {
        d.u32(offset as u32 | ((bits as u32 - 1) << 16) | (channel as u32) << 24);
        // samplePosition0..3 all 0.
        d.u32(0);
        d.u32(lower);
        d.u32(upper);
    }
    d
}

/// Key/value data: each pair as keyAndValueByteLength, key, NUL, value, padded to 4 bytes; keys
/// sorted (as the specification requires).
fn key_value_data(pairs: &mut [(&str, Vec<u8>)]) -> Vec<u8> {
    pairs.sort_by(|a, b| a.0.cmp(b.0));
    let mut d = Vec::new();
    for (key, value) in pairs.iter() {
        d.u32((key.len() + 1 + value.len()) as u32);
        d.extend_from_slice(key.as_bytes());
        d.push(0);
        d.extend_from_slice(value);
        d.resize(d.len().next_multiple_of(4), 0);
    }
    d
}

/// Encodes `texture` as a KTX 2.0 file with one mip level, its `KTXwriter` key naming kelvin.
pub fn encode(texture: &Texture, supercompression: Supercompression) -> Result<Vec<u8>, Ktx2Error> {
    let Texture { format, width, height, depth, texels } = *texture;
    let count = (width as u64) * (height as u64) * (depth.max(1) as u64);
    if width == 0 || height == 0 || count != texels.len() as u64 || count > (u32::MAX / 4) as u64 {
        return Err(Ktx2Error::Size { width, height, depth, len: texels.len() });
    }
    let mut raw = Vec::with_capacity(texels.len() * 4);
    for t in texels {
        raw.u32(format.pack(*t));
    }
    let (scheme, level) = match supercompression {
        Supercompression::None => (0, raw.clone()),
        Supercompression::Zstd(l) => {
            (ZSTD_SCHEME, zstd::bulk::compress(&raw, l).map_err(|e| Ktx2Error::Zstd(e.to_string()))?)
        }
    };
    let writer = format!("kelvin {}\0", env!("CARGO_PKG_VERSION")).into_bytes();
    let dfd = data_format_descriptor(format);
    let kvd = key_value_data(&mut [("KTXwriter", writer)]);
    // Header and index (80 bytes), one level index entry (24), then the descriptor and key/values.
    let dfd_offset = 80 + 24;
    let kvd_offset = dfd_offset + dfd.len();
    // Both are multiples of 4, so the level needs no mipPadding (lcm(4, 4) = 4; 1 when supercompressed).
    let level_offset = kvd_offset + kvd.len();
    let mut f = Vec::with_capacity(level_offset + level.len());
    f.extend_from_slice(&IDENTIFIER);
    for v in [format.vk_format(), 4, width, height, depth, 0, 1, 1, scheme] {
        // typeSize 4 (PACK32), layerCount 0, faceCount 1, levelCount 1.
        f.u32(v);
    }
    f.u32(dfd_offset as u32);
    f.u32(dfd.len() as u32);
    f.u32(kvd_offset as u32);
    f.u32(kvd.len() as u32);
    // No supercompression global data: sgdByteOffset and sgdByteLength 0.
    f.u64(0);
    f.u64(0);
    f.u64(level_offset as u64);
    f.u64(level.len() as u64);
    f.u64(raw.len() as u64);
    f.extend_from_slice(&dfd);
    f.extend_from_slice(&kvd);
    f.extend_from_slice(&level);
    Ok(f)
}

/// Shared-exponent RGB (Vulkan's "Shared Exponent" conversion, after OpenGL's
/// EXT_texture_shared_exponent): 9-bit mantissas without implicit 1, exponent bias 15, channels
/// clamped to [0, 65408] (NaN to 0), mantissas rounded to nearest.
pub fn pack_e5b9g9r9(rgb: Vec3) -> u32 {
    const N: i32 = 9;
    const B: i32 = 15;
    // (2^N - 1) / 2^N * 2^(Emax - B) with Emax = 31.
    let max = 65408.0f32;
    // `max(0)` first: NaN compares false, so it becomes 0.
    let c = rgb.to_array().map(|x| if x > 0.0 { x.min(max) } else { 0.0 });
    let largest = c[0].max(c[1]).max(c[2]);
    // floor(log2(largest)) from the f32's exponent field (exact, where log2 could round up).
    let floor_log2 = ((largest.to_bits() >> 23) as i32 - 127).max(-B - 1);
    let mut exp = floor_log2 + 1 + B;
    let scale = |e: i32| 2f32.powi(e - B - N);
    if (largest / scale(exp) + 0.5).floor() as u32 == 1 << N {
        exp += 1;
    }
    let m = c.map(|x| (x / scale(exp) + 0.5).floor() as u32);
    m[0] | m[1] << 9 | m[2] << 18 | (exp as u32) << 27
}

/// The RGB of a shared-exponent texel: mantissa x 2^(exponent - 15 - 9).
pub fn unpack_e5b9g9r9(texel: u32) -> Vec3 {
    let scale = 2f32.powi((texel >> 27) as i32 - 24);
    Vec3::new((texel & 511) as f32, (texel >> 9 & 511) as f32, (texel >> 18 & 511) as f32) * scale
}

/// An unsigned float with a 5-bit exponent (bias 15) and `m` mantissa bits, from `x` rounded to
/// nearest even; negative and NaN become 0, values past the largest finite one that largest.
fn pack_ufloat(x: f32, m: u32) -> u32 {
    let largest = (30 << m) | ((1 << m) - 1);
    if !(x > 0.0) {
        return 0;
    }
    if x >= unpack_ufloat(largest, m) {
        return largest;
    }
    let bits = x.to_bits();
    let e = (bits >> 23) as i32 - 127;
    if e < -14 {
        // Denormal: mantissa = x / 2^-14 * 2^m (exact scaling by a power of two, then rounding;
        // a round up to 2^m is the smallest normal's encoding).
        return (x * 2f32.powi(14 + m as i32)).round_ties_even() as u32;
    }
    let shift = 23 - m;
    let (mantissa, rest) = ((bits & 0x7f_ffff) >> shift, bits & ((1 << shift) - 1));
    let mut v = ((e + 15) as u32) << m | mantissa;
    let half = 1 << (shift - 1);
    if rest > half || (rest == half && v & 1 == 1) {
        // A carry out of the mantissa steps the exponent, as it should.
        v += 1;
    }
    v
}

/// The value of an unsigned float with a 5-bit exponent and `m` mantissa bits.
fn unpack_ufloat(v: u32, m: u32) -> f32 {
    let (e, mantissa) = (v >> m, v & ((1 << m) - 1));
    let fraction = mantissa as f32 / (1 << m) as f32;
    match e {
        0 => fraction * 2f32.powi(-14),
        31 if mantissa == 0 => f32::INFINITY,
        31 => f32::NAN,
        _ => (1.0 + fraction) * 2f32.powi(e as i32 - 15),
    }
}

/// R and G as 11-bit (6-bit mantissa), B as 10-bit (5-bit mantissa) unsigned floats, R in the
/// low bits.
pub fn pack_b10g11r11(rgb: Vec3) -> u32 {
    pack_ufloat(rgb.x, 6) | pack_ufloat(rgb.y, 6) << 11 | pack_ufloat(rgb.z, 5) << 22
}

/// The RGB of a B10G11R11 texel.
pub fn unpack_b10g11r11(texel: u32) -> Vec3 {
    Vec3::new(unpack_ufloat(texel & 0x7ff, 6), unpack_ufloat(texel >> 11 & 0x7ff, 6), unpack_ufloat(texel >> 22, 5))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hand-packed values: 1.0 is exponent 15 with mantissa 0 in the small floats, mantissa 256
    /// with exponent 16 in the shared-exponent format.
    #[test]
    fn known_values_pack_by_hand() {
        assert_eq!(pack_b10g11r11(Vec3::ONE), 0x3c0 | 0x3c0 << 11 | 0x1e0 << 22);
        assert_eq!(pack_e5b9g9r9(Vec3::ONE), 256 | 256 << 9 | 256 << 18 | 16 << 27);
        // 0.5, 2, 0: mantissas 64, 256, 0 under exponent 17 (2 = 256 x 2^(17 - 24)).
        assert_eq!(pack_e5b9g9r9(Vec3::new(0.5, 2.0, 0.0)), 64 | 256 << 9 | 17 << 27);
        // 65024 is the largest 11-bit float (e 30, m 63); 64512 the largest 10-bit one.
        assert_eq!(pack_b10g11r11(Vec3::new(65024.0, 1e9, f32::INFINITY)), 0x7bf | 0x7bf << 11 | 0x3df << 22);
        assert_eq!(pack_b10g11r11(Vec3::new(-1.0, f32::NAN, 0.0)), 0);
        assert_eq!(pack_e5b9g9r9(Vec3::new(-1.0, f32::NAN, 0.0)), 0);
        // The smallest 11-bit denormal, 2^-20, and half of it (a tie, to even: 0).
        assert_eq!(pack_b10g11r11(Vec3::new(2f32.powi(-20), 2f32.powi(-21), 0.0)), 1);
        // 1 + 1/128 is halfway between 1 and 1 + 1/64: to even, 1. 1 + 3/128: to 1 + 2/64.
        assert_eq!(pack_ufloat(1.0 + 1.0 / 128.0, 6), 15 << 6);
        assert_eq!(pack_ufloat(1.0 + 3.0 / 128.0, 6), 15 << 6 | 2);
        // Rounding up carries into the exponent: just under 2 becomes 2.
        assert_eq!(pack_ufloat(1.999, 6), 16 << 6);
    }

    /// Every representable value round-trips, and any value packs to a nearest representable one.
    #[test]
    fn packing_round_trips_within_half_a_step() {
        for v in 0..0x7c0u32 {
            assert_eq!(pack_ufloat(unpack_ufloat(v, 6), 6), v);
        }
        for v in 0..0x3e0u32 {
            assert_eq!(pack_ufloat(unpack_ufloat(v, 5), 5), v);
        }
        let mut rng = crate::rng::SplitMix64::new(4);
        for _ in 0..10_000 {
            let x = rng.log_range(1e-6, 6e4);
            let packed = unpack_ufloat(pack_ufloat(x, 6), 6);
            // Relative step of a 6-bit mantissa is 2^-6; half of it bounds the error of normals.
            assert!((packed - x).abs() <= x * 2f32.powi(-7) + 2f32.powi(-21), "{x} -> {packed}");
            let rgb = Vec3::new(x, x * rng.f32(), x * rng.f32());
            let texel = pack_e5b9g9r9(rgb);
            // The smallest exponent that holds the largest channel (its mantissa uses the top
            // bit unless the exponent is 0), and every channel rounded to nearest under it.
            let exponent = (texel >> 27) as i32;
            assert!(texel & 511 >= 256 || exponent == 0, "{rgb} -> {texel:#x}");
            let step = 2f32.powi(exponent - 24);
            let shared = unpack_e5b9g9r9(texel);
            assert!((shared - rgb).abs().max_element() <= 0.5 * step * (1.0 + 1e-5), "{rgb} -> {shared}");
        }
    }
}
