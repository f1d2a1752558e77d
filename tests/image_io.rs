//! Image input and output: the real environment maps in tests/data/env, exact EXR round trips, PNG and HDR
//! output, the validation policy on bad files, and the lat-long mapping.

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::{Vec2, Vec3};
use kelvin::render::film_io::{ImageIoError, write_exr, write_hdr, write_image, write_png};
use kelvin::rng::SplitMix64;
use kelvin::scene::image::{
    ImageError, direction_to_lat_long, lat_long_direction, load_image, load_image_from_bytes, srgb_decode,
};

mod common;
use common::files::{TempDir, test_data};

fn temp_dir(test: &str) -> TempDir {
    TempDir::new("image-io", test)
}

fn env_dir() -> PathBuf {
    test_data("env")
}

/// Writes an RGB f32 EXR directly with the exr crate, bypassing kelvin's writer (which has no say on NaN).
fn write_raw_exr(path: &Path, width: usize, height: usize, rgb: &[Vec3]) {
    exr::prelude::write_rgb_file(path, width, height, |x, y| {
        let p = rgb[y * width + x];
        (p.x, p.y, p.z)
    })
    .expect("write raw exr");
}

#[test]
fn real_env_maps_load_with_expected_size_and_dynamic_range() {
    let dir = env_dir();
    // (file, width, height, expected max/mean luminance range or None)
    let cases = [
        ("spiaggia_di_mondello_1k.hdr", 1024, 512, Some((3e4, 3e5))),
        ("luxcore/imagemap-00000.exr", 1024, 512, Some((4e4, 4e5))),
        ("luxcore/sky.exr", 1024, 512, None),
        ("radeonprorender/envLightImage.exr", 2000, 1000, None),
    ];
    for (file, width, height, ratio_range) in cases {
        let path = dir.join(file);
        let start = Instant::now();
        let loaded = load_image(&path).unwrap_or_else(|e| panic!("{e}"));
        let seconds = start.elapsed().as_secs_f64();
        let img = &loaded.image;
        assert_eq!((img.width, img.height), (width, height), "{file}");
        assert_eq!(img.pixels.len(), width * height);
        assert!(img.pixels.iter().all(|p| p.is_finite() && p.cmpge(Vec3::ZERO).all()), "{file}");
        let (max, mean) = (img.max_luminance() as f64, img.mean_luminance());
        let max_rgb = img.pixels.iter().map(|p| p.max_element()).fold(0.0, f32::max);
        eprintln!(
            "{file}: {width}x{height}, max Y {max:.4e}, mean Y {mean:.4e}, max/mean {:.3e}, max channel {max_rgb:.4e}, \
             warnings {:?}, loaded in {:.1} ms",
            max / mean,
            loaded.warnings,
            seconds * 1e3
        );
        if let Some((lo, hi)) = ratio_range {
            assert!((lo..hi).contains(&(max / mean)), "{file}: max/mean {} outside [{lo}, {hi}]", max / mean);
        }
    }
}

#[test]
fn exr_write_read_round_trip_is_bit_exact() {
    let dir = temp_dir("exr-round-trip");
    let (w, h) = (37, 23);
    let mut rng = SplitMix64::new(7);
    let mut rgb: Vec<Vec3> =
        (0..w * h).map(|_| Vec3::new(rng.f32(), rng.f32() * 1e4, (rng.f32() * 80.0 - 40.0).exp2())).collect();
    rgb[0] = Vec3::new(0.0, f32::MIN_POSITIVE / 8.0, f32::MAX); // zero, a subnormal, the largest finite
    let path = dir.join("round_trip.exr");
    write_exr(&path, w, h, &rgb).unwrap();
    let loaded = load_image(&path).unwrap();
    assert!(loaded.warnings.is_empty());
    assert_eq!((loaded.image.width, loaded.image.height), (w, h));
    for (i, (a, b)) in rgb.iter().zip(&loaded.image.pixels).enumerate() {
        assert_eq!(a.to_array().map(f32::to_bits), b.to_array().map(f32::to_bits), "pixel {i}");
    }
    // Row 0 is the top row in both directions.
    assert_eq!(loaded.image.get(1, 0), rgb[1]);
    assert_eq!(loaded.image.get(0, 1), rgb[w]);
}

#[test]
fn png_write_gives_the_documented_tone_curve() {
    let dir = temp_dir("png");
    let (w, h) = (4, 3);
    // Greys of luminance L map to L / (1 + L): 0, 1/3, 1/2, 3/4, then sRGB-encoded to 8 bits.
    let greys = [0.0f32, 0.5, 1.0, 3.0];
    let rgb: Vec<Vec3> = (0..w * h).map(|i| Vec3::splat(greys[i % w])).collect();
    let path = dir.join("tone.png");
    write_png(&path, w, h, &rgb, 0.0).unwrap();
    let back = load_image(&path).unwrap().image;
    assert_eq!((back.width, back.height), (w, h));
    for (x, &l) in greys.iter().enumerate() {
        let expected = l / (1.0 + l);
        let got = back.get(x, 2).x;
        // One 8-bit step in sRGB is under 1% of the value above 0.05 (and exact at 0).
        assert!((got - expected).abs() <= 0.01 * expected + 1e-6, "L {l}: got {got}, expected {expected}");
    }
    // One stop of exposure doubles the input: L = 0.5 at +1 stop looks like L = 1.
    write_png(&path, w, h, &rgb, 1.0).unwrap();
    let brighter = load_image(&path).unwrap().image;
    assert_eq!(brighter.get(1, 0), back.get(2, 0));
}

#[test]
fn hdr_write_read_round_trip_within_rgbe_precision() {
    let dir = temp_dir("hdr");
    let (w, h) = (16, 8);
    let mut rng = SplitMix64::new(11);
    let rgb: Vec<Vec3> = (0..w * h).map(|_| Vec3::splat(rng.f32() * 100.0 + 1e-3)).collect();
    let path = dir.join("rt.hdr");
    write_image(&path, w, h, &rgb, 0.0).unwrap();
    let back = load_image(&path).unwrap().image;
    for (a, b) in rgb.iter().zip(&back.pixels) {
        assert!(((*a - *b).abs() / *a).max_element() < 1.0 / 128.0, "{a} vs {b}");
    }
    // A negative value is written as 0 (RGBE cannot hold it).
    write_hdr(&path, 1, 1, &[Vec3::new(-1.0, 2.0, 0.0)]).unwrap();
    assert_eq!(load_image(&path).unwrap().image.get(0, 0), Vec3::new(0.0, 2.0, 0.0));
}

#[test]
fn writer_rejects_unknown_extension_and_wrong_pixel_count() {
    let dir = temp_dir("writer-errors");
    let err = write_image(&dir.join("out.tiff"), 1, 1, &[Vec3::ONE], 0.0).unwrap_err();
    assert!(matches!(err, ImageIoError::UnknownExtension { .. }));
    assert!(err.to_string().contains("out.tiff") && err.to_string().contains("\"tiff\""), "{err}");
    let err = write_exr(&dir.join("a.exr"), 2, 2, &[Vec3::ONE; 3]).unwrap_err();
    assert!(matches!(err, ImageIoError::SizeMismatch { len: 3, .. }), "{err}");
    let err = write_png(&dir.join("a.png"), 0, 0, &[], 0.0).unwrap_err();
    assert!(matches!(err, ImageIoError::BadSize { .. }), "{err}");
    let err = write_exr(&dir.join("no/such/dir/a.exr"), 1, 1, &[Vec3::ONE]).unwrap_err();
    assert!(matches!(err, ImageIoError::Io { .. }) && err.to_string().contains("a.exr"), "{err}");
}

#[test]
fn nan_and_infinite_pixels_are_rejected_naming_the_first_one() {
    let dir = temp_dir("nan");
    let (w, h) = (8, 6);
    let mut rgb = vec![Vec3::splat(0.5); w * h];
    rgb[2 * w + 3] = Vec3::new(0.5, f32::NAN, 0.5);
    rgb[4 * w + 5] = Vec3::new(f32::INFINITY, 0.5, 0.5);
    rgb[5 * w + 1] = Vec3::new(0.5, 0.5, f32::NEG_INFINITY);
    let path = dir.join("nan.exr");
    write_raw_exr(&path, w, h, &rgb);
    let err = load_image(&path).unwrap_err();
    assert!(matches!(err, ImageError::NonFinite { x: 3, y: 2, count: 3, .. }), "{err:?}");
    let msg = err.to_string();
    assert!(msg.contains("nan.exr") && msg.contains("(x 3, y 2)") && msg.contains("3 pixel"), "{msg}");
    eprintln!("{msg}");
}

#[test]
fn exr_half_tiled_layered_and_grey_files_load() {
    use exr::prelude::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, SmallVec, SpecificChannels, f16};
    use exr::prelude::{LayerAttributes, WritableImage};
    let dir = temp_dir("exr-variants");
    let (w, h) = (70, 67); // more than one 64x64 tile each way
    let value = |x: usize, y: usize| Vec3::new(x as f32 * 0.25, y as f32 * 0.5, 1.5);

    // f16 RGB in 64x64 tiles (RLE).
    let path = dir.join("half_tiled.exr");
    let channels = SpecificChannels::rgb(|exr::math::Vec2(x, y): exr::math::Vec2<usize>| {
        let v = value(x, y);
        (f16::from_f32(v.x), f16::from_f32(v.y), f16::from_f32(v.z))
    });
    Image::from_encoded_channels((w, h), Encoding::FAST_LOSSLESS, channels).write().to_file(&path).unwrap();
    let img = load_image(&path).unwrap().image;
    assert_eq!((img.width, img.height), (w, h));
    // These values are exact in f16.
    assert_eq!(img.get(69, 66), value(69, 66));
    assert_eq!(img.get(3, 65), value(3, 65));

    // u32 Y only: grey.
    let path = dir.join("grey_u32.exr");
    let ys: Vec<u32> = (0..w * h).map(|i| i as u32).collect();
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> =
        SmallVec::from_vec(vec![AnyChannel::new("Y", FlatSamples::U32(ys))]);
    Image::from_channels((w, h), AnyChannels::sort(list)).write().to_file(&path).unwrap();
    let img = load_image(&path).unwrap().image;
    assert_eq!(img.get(5, 2), Vec3::splat((2 * w + 5) as f32));

    // A file whose only colour is in "diffuse.R/G/B" next to an unrelated "depth.Z".
    let path = dir.join("layered.exr");
    let plane = |f: fn(Vec3) -> f32| FlatSamples::F32((0..w * h).map(|i| f(value(i % w, i / w))).collect());
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::from_vec(vec![
        AnyChannel::new("depth.Z", plane(|_| 9.0)),
        AnyChannel::new("diffuse.R", plane(|v| v.x)),
        AnyChannel::new("diffuse.G", plane(|v| v.y)),
        AnyChannel::new("diffuse.B", plane(|v| v.z)),
    ]);
    let layer =
        exr::prelude::Layer::new((w, h), LayerAttributes::default(), Encoding::SMALL_LOSSLESS, AnyChannels::sort(list));
    Image::from_layer(layer).write().to_file(&path).unwrap();
    assert_eq!(load_image(&path).unwrap().image.get(10, 20), value(10, 20));

    // Only a Z channel: an error listing what was found.
    let path = dir.join("depth_only.exr");
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::from_vec(vec![AnyChannel::new("Z", plane(|_| 1.0))]);
    Image::from_channels((w, h), AnyChannels::sort(list)).write().to_file(&path).unwrap();
    let err = load_image(&path).unwrap_err();
    assert!(matches!(err, ImageError::NoColorChannels { .. }) && err.to_string().contains("found: Z"), "{err}");
}

#[test]
fn negative_pixels_are_clamped_with_a_warning() {
    let dir = temp_dir("negative");
    let mut rgb = vec![Vec3::splat(0.25); 6];
    rgb[1] = Vec3::new(-0.1, 0.2, 0.3);
    rgb[4] = Vec3::new(0.1, 0.2, -3.0);
    let path = dir.join("negative.exr");
    write_exr(&path, 3, 2, &rgb).unwrap();
    let loaded = load_image(&path).unwrap();
    assert_eq!(loaded.image.get(1, 0), Vec3::new(0.0, 0.2, 0.3));
    assert_eq!(loaded.image.get(1, 1), Vec3::new(0.1, 0.2, 0.0));
    assert_eq!(loaded.image.get(0, 0), Vec3::splat(0.25));
    assert_eq!(loaded.warnings.len(), 1);
    assert!(loaded.warnings[0].contains("negative.exr") && loaded.warnings[0].contains("2 pixel"), "{:?}", loaded);
}

#[test]
fn truncated_files_give_errors_not_panics() {
    let dir = temp_dir("truncated");
    let (w, h) = (9, 5);
    let mut rng = SplitMix64::new(3);
    let rgb: Vec<Vec3> = (0..w * h).map(|_| Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 4.0).collect();
    for ext in ["exr", "hdr", "png"] {
        let path = dir.join(format!("whole.{ext}"));
        write_image(&path, w, h, &rgb, 0.0).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let whole = load_image_from_bytes(&bytes, ext, "whole").unwrap().image;
        // Every proper prefix is an error or, when only a trailer is cut (PNG's IEND), the whole image: never a
        // panic, never a silently partial image.
        let mut loaded_prefixes = 0;
        for len in 0..bytes.len() {
            if let Ok(loaded) = load_image_from_bytes(&bytes[..len], ext, "prefix") {
                assert_eq!(loaded.image, whole, "{ext} cut to {len} of {} bytes loaded partially", bytes.len());
                loaded_prefixes += 1;
            }
        }
        eprintln!("{ext}: {} bytes, {loaded_prefixes} prefixes load (complete pixel data), the rest fail", bytes.len());
        // Through the file path, the error names the file.
        let cut = dir.join(format!("cut.{ext}"));
        std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
        let err = load_image(&cut).unwrap_err();
        assert!(matches!(err, ImageError::Decode { .. }) && err.to_string().contains("cut."), "{err}");
        eprintln!("{err}");
    }
    // A real map cut in half.
    let env = env_dir();
    for file in ["spiaggia_di_mondello_1k.hdr", "luxcore/imagemap-00000.exr"] {
        let bytes = std::fs::read(env.join(file)).unwrap();
        let ext = Path::new(file).extension().unwrap().to_str().unwrap();
        let err = load_image_from_bytes(&bytes[..bytes.len() / 2], ext, file).unwrap_err();
        assert!(matches!(err, ImageError::Decode { .. }), "{err}");
    }
}

#[test]
fn missing_empty_and_unknown_files_give_clear_errors() {
    let dir = temp_dir("missing");
    let missing = dir.join("no_such_map.exr");
    let err = load_image(&missing).unwrap_err();
    assert!(matches!(err, ImageError::NotFound { .. }) && err.to_string().contains("no_such_map.exr"), "{err}");

    let empty = dir.join("empty.hdr");
    std::fs::write(&empty, b"").unwrap();
    let err = load_image(&empty).unwrap_err();
    assert!(matches!(err, ImageError::Empty { .. }) && err.to_string().contains("empty.hdr"), "{err}");

    let unknown = dir.join("map.tga");
    std::fs::write(&unknown, b"xxxx").unwrap();
    let err = load_image(&unknown).unwrap_err();
    assert!(matches!(err, ImageError::UnknownFormat { .. }) && err.to_string().contains("map.tga"), "{err}");

    let garbage = dir.join("garbage.png");
    std::fs::write(&garbage, b"this is not a png").unwrap();
    assert!(matches!(load_image(&garbage).unwrap_err(), ImageError::Decode { .. }));

    // A header claiming 100000 x 100000 pixels is refused before any pixel is decoded.
    let header = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000 +X 100000\n\x02\x02\x00\x10";
    let err = load_image_from_bytes(header, "hdr", "huge.hdr").unwrap_err();
    assert!(matches!(err, ImageError::TooLarge { width: 100000, .. }), "{err}");

    // A directory is unreadable as a file.
    let folder = dir.join("folder.exr");
    std::fs::create_dir_all(&folder).unwrap();
    assert!(matches!(load_image(&folder).unwrap_err(), ImageError::Io { .. }));
}

#[test]
fn tiny_images_load() {
    let dir = temp_dir("tiny");
    for (w, h) in [(1, 1), (1, 7), (7, 1)] {
        let rgb: Vec<Vec3> = (0..w * h).map(|i| Vec3::new(i as f32, 1.0, 2.0)).collect();
        for ext in ["exr", "hdr", "png"] {
            let path = dir.join(format!("tiny_{w}x{h}.{ext}"));
            write_image(&path, w, h, &rgb, 0.0).unwrap();
            let img = load_image(&path).unwrap_or_else(|e| panic!("{e}")).image;
            assert_eq!((img.width, img.height), (w, h), "{ext}");
            // Bilinear lookups anywhere (and outside [0,1]) stay finite.
            for uv in [Vec2::ZERO, Vec2::ONE, Vec2::new(-3.2, 7.5), Vec2::splat(0.5)] {
                assert!(img.bilinear(uv).is_finite());
            }
        }
    }
}

#[test]
fn bilinear_wraps_in_u_and_clamps_in_v() {
    let dir = temp_dir("bilinear");
    let rgb = vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE]; // 2 x 2: row 0 = (X, Y), row 1 = (Z, 1)
    let path = dir.join("b.exr");
    write_exr(&path, 2, 2, &rgb).unwrap();
    let img = load_image(&path).unwrap().image;
    // Pixel centres are exact.
    assert_eq!(img.bilinear(Vec2::new(0.25, 0.25)), Vec3::X);
    assert_eq!(img.bilinear(Vec2::new(0.75, 0.75)), Vec3::ONE);
    // u = 0 lies half-way between the last and first columns (wrap); v = 0 clamps to row 0.
    assert_eq!(img.bilinear(Vec2::new(0.0, 0.0)), (Vec3::X + Vec3::Y) / 2.0);
    assert_eq!(img.bilinear(Vec2::new(1.0, 1.0)), (Vec3::Z + Vec3::ONE) / 2.0);
    assert!((img.luminance(0, 1) - 0.0721750).abs() < 1e-7);
}

#[test]
fn sixteen_bit_png_is_decoded_with_the_srgb_curve() {
    let dir = temp_dir("png16");
    let values: [u16; 3] = [0, 32768, 65535];
    let buffer = image::ImageBuffer::<image::Rgb<u16>, Vec<u16>>::from_raw(1, 1, values.to_vec()).unwrap();
    let path = dir.join("16.png");
    buffer.save(&path).unwrap();
    let img = load_image(&path).unwrap().image;
    let expected = values.map(|v| srgb_decode(v as f64 / 65535.0) as f32);
    assert_eq!(img.get(0, 0).to_array(), expected);
}

#[test]
fn jpeg_from_memory_is_decoded_with_the_srgb_curve() {
    use image::ImageEncoder;
    let grey = vec![128u8; 8 * 8 * 3];
    let mut bytes = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 95)
        .write_image(&grey, 8, 8, image::ExtendedColorType::Rgb8)
        .unwrap();
    let img = load_image_from_bytes(&bytes, "image/jpeg", "embedded texture 0").unwrap().image;
    let expected = srgb_decode(128.0 / 255.0) as f32;
    assert!(img.pixels.iter().all(|p| (*p - Vec3::splat(expected)).abs().max_element() < 0.01), "{:?}", img.get(0, 0));
    let err = load_image_from_bytes(&bytes, "image/webp", "embedded texture 0").unwrap_err();
    assert!(err.to_string().contains("embedded texture 0") && err.to_string().contains("webp"), "{err}");
}

#[test]
fn corrupted_bytes_never_panic() {
    let dir = temp_dir("corrupt");
    let mut rng = SplitMix64::new(99);
    let rgb: Vec<Vec3> = (0..12 * 10).map(|_| Vec3::new(rng.f32(), rng.f32(), rng.f32())).collect();
    for ext in ["exr", "hdr", "png"] {
        let path = dir.join(format!("c.{ext}"));
        write_image(&path, 12, 10, &rgb, 0.0).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let mut failures = 0;
        for _ in 0..300 {
            let mut bad = bytes.clone();
            for _ in 0..1 + rng.next_u64() % 4 {
                let i = rng.below(bad.len());
                bad[i] = rng.next_u64() as u8;
            }
            // Ok (a changed pixel) or an error; either way validated and never a panic.
            match load_image_from_bytes(&bad, ext, "mutated") {
                Ok(l) => assert!(l.image.pixels.iter().all(|p| p.is_finite() && p.cmpge(Vec3::ZERO).all())),
                Err(_) => failures += 1,
            }
        }
        eprintln!("{ext}: {failures} of 300 mutated files rejected, the rest loaded valid pixels");
    }
}

#[test]
fn lat_long_mapping_round_trips_and_matches_the_stated_convention() {
    let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-6;
    assert!(close(lat_long_direction(Vec2::new(0.5, 0.5)), Vec3::X));
    assert!(close(lat_long_direction(Vec2::new(0.75, 0.5)), Vec3::Z));
    assert!(close(lat_long_direction(Vec2::new(0.25, 0.5)), Vec3::NEG_Z));
    assert!(close(lat_long_direction(Vec2::new(0.0, 0.5)), Vec3::NEG_X));
    assert!(close(lat_long_direction(Vec2::new(0.3, 0.0)), Vec3::Y));
    assert!(close(lat_long_direction(Vec2::new(0.3, 1.0)), Vec3::NEG_Y));
    assert_eq!(direction_to_lat_long(Vec3::NEG_Z), Vec2::new(0.25, 0.5));
    assert_eq!(direction_to_lat_long(Vec3::Y * 3.0), Vec2::new(0.5, 0.0));
    assert_eq!(direction_to_lat_long(Vec3::ZERO), Vec2::new(0.5, 0.5));
    let seam = direction_to_lat_long(Vec3::NEG_X);
    assert!((0.0..1.0).contains(&seam.x));

    let mut rng = SplitMix64::new(5);
    let (mut worst_dir, mut worst_uv) = (0.0f32, 0.0f32);
    for _ in 0..100_000 {
        let uv = rng.vec2();
        let dir = lat_long_direction(uv);
        assert!((dir.length() - 1.0).abs() < 1e-6);
        let back = direction_to_lat_long(dir);
        assert!((0.0..1.0).contains(&back.x) && (0.0..=1.0).contains(&back.y));
        worst_dir = worst_dir.max((lat_long_direction(back) - dir).length());
        // u is undefined at the poles; compare it away from them, modulo the seam.
        if (0.01..0.99).contains(&uv.y) {
            let du = (back.x - uv.x).abs();
            worst_uv = worst_uv.max(du.min(1.0 - du)).max((back.y - uv.y).abs());
        }
    }
    eprintln!("lat-long round trip: worst direction error {worst_dir:.2e}, worst uv error {worst_uv:.2e}");
    assert!(worst_dir < 1e-6 && worst_uv < 1e-6, "{worst_dir} {worst_uv}");
}

#[test]
fn read_exr_gives_back_exactly_what_write_exr_wrote_negatives_included() {
    use kelvin::render::film_io::{read_exr, write_exr};
    let dir = std::env::temp_dir().join(format!("kelvin-read-exr-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("exact.exr");
    let rgb: Vec<glam::Vec3> =
        (0..12).map(|i| glam::Vec3::new(i as f32 * 0.37 - 2.0, -1e-7 * i as f32, 1e5 / (i + 1) as f32)).collect();
    write_exr(&path, 4, 3, &rgb).unwrap();
    let (w, h, back) = read_exr(&path).unwrap();
    assert_eq!((w, h), (4, 3));
    assert_eq!(back, rgb);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Blocks decompressed in parallel land where the exr crate's own reader puts them: every texel of
/// the real EXR maps, and of files in each lossless and lossy compression, in scan lines (both
/// line orders) and in tiles, bit for bit, on one thread and on two.
#[test]
fn parallel_exr_decode_equals_the_exr_crates_reader_bit_for_bit() {
    use exr::prelude::{Blocks, Compression, Encoding, Image, LineOrder, SpecificChannels, WritableImage, f16};
    let dir = temp_dir("exr-parallel");
    let mut files: Vec<PathBuf> =
        ["luxcore/imagemap-00000.exr", "luxcore/sky.exr", "radeonprorender/envLightImage.exr"]
            .map(|rel| env_dir().join(rel))
            .to_vec();
    let (w, h) = (301, 203); // partial blocks at the right and bottom edges
    let value = |x: usize, y: usize| {
        let (u, v) = (x as f32 / w as f32, y as f32 / h as f32);
        Vec3::new(u * 40.0 + (v * 31.0).sin() + 1.0, v * 3.0, (u * v * 17.0).cos() + 1.5)
    };
    let compressions = [Compression::RLE, Compression::ZIP16, Compression::PIZ, Compression::PXR24, Compression::B44];
    for (k, compression) in compressions.into_iter().enumerate() {
        let blocks = [Blocks::ScanLines, Blocks::Tiles(exr::math::Vec2(32, 16))][k % 2];
        let line_order = [LineOrder::Increasing, LineOrder::Decreasing][k / 2 % 2];
        let path = dir.join(format!("variant_{k}.exr"));
        let channels = SpecificChannels::rgb(|exr::math::Vec2(x, y): exr::math::Vec2<usize>| {
            let v = value(x, y);
            (f16::from_f32(v.x), f16::from_f32(v.y), f16::from_f32(v.z))
        });
        let encoding = Encoding { compression, blocks, line_order };
        Image::from_encoded_channels((w, h), encoding, channels).write().to_file(&path).unwrap();
        files.push(path);
    }
    for path in &files {
        let reference = exr::prelude::read_first_rgba_layer_from_file(
            path,
            |size, _| (size.width(), vec![Vec3::ZERO; size.area()]),
            |(width, pixels): &mut (usize, Vec<Vec3>), p, (r, g, b, _): (f32, f32, f32, f32)| {
                // The loader's documented rule: a texel with a negative component is clamped to 0
                // (B44 is lossy and gives a few near zero).
                let v = Vec3::new(r, g, b);
                pixels[p.y() * *width + p.x()] = if v.cmplt(Vec3::ZERO).any() { v.max(Vec3::ZERO) } else { v }
            },
        )
        .unwrap()
        .layer_data
        .channel_data
        .pixels
        .1;
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let image = pool.install(|| load_image(path)).unwrap().image;
            assert_eq!(image.pixels.len(), reference.len());
            let bits = |v: &Vec3| v.to_array().map(f32::to_bits);
            let first = image.pixels.iter().zip(&reference).position(|(a, b)| bits(a) != bits(b));
            assert!(
                first.is_none(),
                "{} on {threads} threads: texel {first:?} {:?}",
                path.display(),
                first.map(|i| (image.pixels[i], reference[i]))
            );
        }
    }
}
