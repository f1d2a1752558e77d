//! `--frames 0..47|1-100x2|1,5,10-20 --fps F [--animation NAME|INDEX]`: which frames of a glTF animation
//! `kelvin render` renders, and the file each one goes to.

use std::path::{Path, PathBuf};
use std::str::FromStr;

/// The most frames one command renders.
const MAX_FRAMES: u32 = 1_000_000;

/// The frames to render, ascending, each once.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FrameRange {
    frames: Vec<u32>,
}

impl FrameRange {
    pub fn iter(&self) -> impl Iterator<Item = u32> + '_ {
        self.frames.iter().copied()
    }

    /// One frame only.
    pub fn is_single(&self) -> bool {
        self.frames.len() == 1
    }
}

impl FromStr for FrameRange {
    type Err = String;

    /// A farm's frame list: items separated by commas, each "A", "A-B" (both included) or "A-BxS"
    /// (every S-th frame from A up to B), as Deadline and Flamenco write them; "A..B" (both
    /// included) is kept too. "1-9x2,20" is 1, 3, 5, 7, 9, 20.
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = |why: &str| format!("'{s}': {why} (frames are like 7, 0..47, 1-100, 1-100x2 or 1,5,10-20)");
        let number =
            |v: &str| v.trim().parse::<u32>().map_err(|_| bad(&format!("{:?} is not a frame number", v.trim())));
        let mut frames = Vec::new();
        for item in s.split(',') {
            let (range, step) = match item.split_once(['x', 'X']) {
                Some((r, step)) => (r, number(step)?),
                None => (item, 1),
            };
            let (first, last) = match range.split_once("..").or_else(|| range.split_once('-')) {
                Some((a, b)) => (number(a)?, number(b)?),
                None if step == 1 => (number(range)?, number(range)?),
                None => return Err(bad("a step needs a range")),
            };
            if last < first {
                return Err(bad(&format!("{last} is before {first}")));
            }
            if step == 0 {
                return Err(bad("a step of 0"));
            }
            if (last - first) / step >= MAX_FRAMES || frames.len() as u32 >= MAX_FRAMES {
                return Err(bad(&format!("more than {MAX_FRAMES} frames")));
            }
            frames.extend((first..=last).step_by(step as usize));
        }
        frames.sort_unstable();
        frames.dedup();
        if frames.len() as u32 > MAX_FRAMES {
            return Err(bad(&format!("more than {MAX_FRAMES} frames")));
        }
        Ok(Self { frames })
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
pub fn frame_output(pattern: &Path, range: &FrameRange, frame: u32) -> Result<PathBuf, String> {
    match frame_path(pattern, frame) {
        Err(_) if range.is_single() => Ok(pattern.to_path_buf()),
        numbered => numbered,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_ranges_and_numbered_names() {
        let frames = |s: &str| s.parse::<FrameRange>().map(|r| r.iter().collect::<Vec<_>>());
        assert_eq!(frames("3..7"), Ok(vec![3, 4, 5, 6, 7]));
        assert_eq!(frames("5"), Ok(vec![5]));
        assert_eq!(frames("1-9x2"), Ok(vec![1, 3, 5, 7, 9]));
        assert_eq!(frames("1-100x2").map(|f| (f.len(), f[0], f[49])), Ok((50, 1, 99)));
        assert_eq!(frames("1,5,10-13"), Ok(vec![1, 5, 10, 11, 12, 13]));
        assert_eq!(frames("4-6, 5, 1"), Ok(vec![1, 4, 5, 6]), "sorted, each once");
        assert!(frames("7..3").unwrap_err().contains("3 is before 7"));
        assert!(frames("a..3").is_err());
        assert!(frames("1-5x0").unwrap_err().contains("step of 0"));
        assert!(frames("5x2").unwrap_err().contains("needs a range"));
        assert!(frames("0-4000000000").unwrap_err().contains("more than"));
        assert_eq!(frame_path(Path::new("dir/out_####.exr"), 7).unwrap(), Path::new("dir/out_0007.exr"));
        assert_eq!(frame_path(Path::new("f#.png"), 123).unwrap(), Path::new("f123.png"));
        // Only the file name's last run counts.
        assert_eq!(frame_path(Path::new("a#/b_##_c_##.exr"), 4).unwrap(), Path::new("a#/b_##_c_04.exr"));
        assert!(frame_path(Path::new("out.exr"), 1).unwrap_err().contains("'#'"));
        // One frame may go to a plain name (as `kelvin batch` plans each frame of a job).
        let one: FrameRange = "4".parse().unwrap();
        assert_eq!(frame_output(Path::new("out.exr"), &one, 4).unwrap(), Path::new("out.exr"));
        assert_eq!(frame_output(Path::new("o_##.exr"), &one, 4).unwrap(), Path::new("o_04.exr"));
        assert!(frame_output(Path::new("out.exr"), &"4..5".parse().unwrap(), 4).is_err());
    }
}
