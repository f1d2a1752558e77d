//! Parsers of the command line's values. Each refuses a value outside its range with a message that
//! names the value and the range; clap puts the option's name in front (`invalid value '0' for
//! '--spp <SPP>': ...`), so no option is taken silently out of range.

use clap::builder::{RangedI64ValueParser, RangedU64ValueParser};
use kelvin::render::tiles::Crop;

use kelvin::render::job::{self, MAX_SIDE};

/// WIDTHxHEIGHT, each in 1..=16384.
pub(super) fn size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("'{s}': expected WIDTHxHEIGHT, e.g. 512x512"))?;
    let parse = |v: &str| v.trim().parse::<u32>().ok().filter(|&n| (1..=MAX_SIDE).contains(&n));
    match (parse(w), parse(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(format!("'{s}': width and height must be whole numbers in 1..={MAX_SIDE}")),
    }
}

/// X,Y,Z, three finite numbers.
pub(super) fn point(s: &str) -> Result<glam::Vec3, String> {
    let v: Vec<f32> = s.split(',').filter_map(|c| c.trim().parse().ok()).collect();
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) && s.split(',').count() == 3 => Ok(glam::Vec3::new(x, y, z)),
        _ => Err(format!("'{s}': expected three finite numbers X,Y,Z")),
    }
}

/// RX,RY,RZ voxels, each in 1..=128.
pub(super) fn resolution(s: &str) -> Result<glam::UVec3, String> {
    let v: Vec<u32> = s.split(',').filter_map(|c| c.trim().parse().ok()).collect();
    match v[..] {
        [x, y, z] if s.split(',').count() == 3 && v.iter().all(|r| kelvin::bake::volume::RESOLUTION.contains(r)) => {
            Ok(glam::UVec3::new(x, y, z))
        }
        _ => Err(format!("'{s}': expected three whole numbers RX,RY,RZ, each in 1..=128")),
    }
}

/// X0,Y0,Z0,X1,Y1,Z1: the corners of a box, finite, each of the first three below its partner.
pub(super) fn bounds(s: &str) -> Result<(glam::Vec3, glam::Vec3), String> {
    let v: Vec<f32> = s.split(',').filter_map(|c| c.trim().parse().ok()).collect();
    match v[..] {
        [x0, y0, z0, x1, y1, z1] if s.split(',').count() == 6 && v.iter().all(|c| c.is_finite()) => {
            let (lo, hi) = (glam::Vec3::new(x0, y0, z0), glam::Vec3::new(x1, y1, z1));
            if lo.cmplt(hi).all() {
                Ok((lo, hi))
            } else {
                Err(format!("'{s}': each of X0,Y0,Z0 must be below X1,Y1,Z1"))
            }
        }
        _ => Err(format!("'{s}': expected six finite numbers X0,Y0,Z0,X1,Y1,Z1")),
    }
}

/// Seconds in 0..1e7.
pub(super) fn seconds(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(t) if t.is_finite() && job::SECONDS.contains(&t) => Ok(t),
        _ => Err(format!("'{s}': expected a number of seconds in [0, 10000000)")),
    }
}

/// Frames per second in (0, 1e6].
pub(super) fn fps(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(f) if f.is_finite() && f > 0.0 && f <= 1e6 => Ok(f),
        _ => Err(format!("'{s}': expected frames per second in (0, 1000000]")),
    }
}

/// X0,Y0,X1,Y1 of a non-empty crop.
pub(super) fn crop(s: &str) -> Result<Crop, String> {
    s.parse().map_err(|e: kelvin::render::tiles::TileError| e.to_string())
}

/// A finite number in `[lo, hi]`.
pub(super) fn finite_in(lo: f32, hi: f32) -> impl Fn(&str) -> Result<f32, String> + Clone + Send + Sync + 'static {
    move |s: &str| match s.trim().parse::<f32>() {
        Ok(x) if x.is_finite() && (lo..=hi).contains(&x) => Ok(x),
        _ => Err(format!("'{s}': expected a number in [{lo}, {hi}]")),
    }
}

/// A whole number in `range` (clap's message: "0 is not in 1..=4294967295").
pub(super) fn whole(range: std::ops::RangeInclusive<u32>) -> RangedI64ValueParser<u32> {
    RangedI64ValueParser::new().range(*range.start() as i64..=*range.end() as i64)
}

/// A count in `range`, for sizes and loops (`usize`).
pub(super) fn count(range: impl std::ops::RangeBounds<u64>) -> RangedU64ValueParser<usize> {
    RangedU64ValueParser::new().range(range)
}

/// Worker threads: 1..=1024.
pub(super) fn threads() -> RangedU64ValueParser<usize> {
    count(1..=1024)
}

/// PNG exposure in stops: [-64, 64].
pub(super) fn exposure() -> impl Fn(&str) -> Result<f32, String> + Clone + Send + Sync + 'static {
    finite_in(-64.0, 64.0)
}

/// A light's intensity multiplier: [0, 1e12].
pub(super) fn intensity() -> impl Fn(&str) -> Result<f32, String> + Clone + Send + Sync + 'static {
    finite_in(*job::INTENSITY.start(), *job::INTENSITY.end())
}

/// The folder of real test data that `bench` and `report` read: it must exist. A crate installed
/// from the registry ships without it (it lives in the repository), so the message says where to get it.
pub(super) fn data_dir(path: &std::path::Path) -> Result<(), String> {
    if path.is_dir() {
        Ok(())
    } else {
        Err(format!(
            "--data {}: not a folder; the scenes are the kelvin repository's tests/data (not shipped in the crate): clone \
             the repository and pass --data <clone>/tests/data",
            path.display()
        ))
    }
}

/// A file read later by name (an environment map): refused at once, named with its option, when
/// it does not exist.
pub(super) fn existing_file(s: &str) -> Result<std::path::PathBuf, String> {
    let path = std::path::PathBuf::from(s);
    match path.metadata() {
        Ok(m) if m.is_dir() => Err("is a folder, not a file".into()),
        Ok(_) => Ok(path),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err("file not found".into()),
        Err(e) => Err(format!("cannot read: {e}")),
    }
}
