//! `--frames FIRST..LAST --fps F [--animation NAME|INDEX]`: which frames of a glTF animation
//! `kelvin render` renders, and the file each one goes to.

use std::path::{Path, PathBuf};
use std::str::FromStr;

/// The most frames one command renders.
const MAX_FRAMES: u32 = 1_000_000;

/// Frames `first..=last`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    pub first: u32,
    pub last: u32,
}

impl FrameRange {
    pub fn iter(self) -> impl Iterator<Item = u32> {
        self.first..=self.last
    }
}

impl FromStr for FrameRange {
    type Err = String;

    /// "A..B" (both included) or "A".
    fn from_str(s: &str) -> Result<Self, String> {
        let number = |v: &str| v.trim().parse::<u32>().map_err(|_| format!("'{s}': expected FIRST..LAST, e.g. 0..47"));
        let (first, last) = match s.split_once("..") {
            Some((a, b)) => (number(a)?, number(b)?),
            None => (number(s)?, number(s)?),
        };
        if last < first {
            return Err(format!("'{s}': the last frame is before the first"));
        }
        if last - first >= MAX_FRAMES {
            return Err(format!("'{s}': more than {MAX_FRAMES} frames"));
        }
        Ok(Self { first, last })
    }
}

/// `pattern` with its file name's last run of '#' replaced by `frame`, zero-padded to the run's
/// length (out_####.exr: out_0007.exr), or an error if the name has no '#'.
pub fn frame_path(pattern: &Path, frame: u32) -> Result<PathBuf, String> {
    let name = pattern.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let end = name.rfind('#').ok_or_else(|| {
        format!(
            "{}: an output for --frames needs a run of '#' for the frame number, e.g. out_####.exr",
            pattern.display()
        )
    })? + 1;
    let start = name[..end].trim_end_matches('#').len();
    let numbered = format!("{}{frame:0width$}{}", &name[..start], &name[end..], width = end - start);
    Ok(pattern.with_file_name(numbered))
}

/// The file frame `frame` of `range` goes to: `frame_path`, or `pattern` itself when the range
/// is one frame and the name has no '#'.
pub fn frame_output(pattern: &Path, range: FrameRange, frame: u32) -> Result<PathBuf, String> {
    match frame_path(pattern, frame) {
        Err(_) if range.first == range.last => Ok(pattern.to_path_buf()),
        numbered => numbered,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_ranges_and_numbered_names() {
        assert_eq!("3..7".parse(), Ok(FrameRange { first: 3, last: 7 }));
        assert_eq!("5".parse(), Ok(FrameRange { first: 5, last: 5 }));
        assert!("7..3".parse::<FrameRange>().unwrap_err().contains("before the first"));
        assert!("a..3".parse::<FrameRange>().is_err());
        assert_eq!(frame_path(Path::new("dir/out_####.exr"), 7).unwrap(), Path::new("dir/out_0007.exr"));
        assert_eq!(frame_path(Path::new("f#.png"), 123).unwrap(), Path::new("f123.png"));
        // Only the file name's last run counts.
        assert_eq!(frame_path(Path::new("a#/b_##_c_##.exr"), 4).unwrap(), Path::new("a#/b_##_c_04.exr"));
        assert!(frame_path(Path::new("out.exr"), 1).unwrap_err().contains("'#'"));
        // One frame may go to a plain name (as `kelvin batch` plans each frame of a job).
        let one = FrameRange { first: 4, last: 4 };
        assert_eq!(frame_output(Path::new("out.exr"), one, 4).unwrap(), Path::new("out.exr"));
        assert_eq!(frame_output(Path::new("o_##.exr"), one, 4).unwrap(), Path::new("o_04.exr"));
        assert!(frame_output(Path::new("out.exr"), FrameRange { first: 4, last: 5 }, 4).is_err());
    }
}
