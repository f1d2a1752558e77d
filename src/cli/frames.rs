//! `--frames 0..47|1-100x2|1,5,10-20|-5--1|1-10y3|1-10:3 --fps F [--animation NAME|INDEX]`: which frames
//! of a glTF animation `kelvin render` renders, and the file each one goes to.
//!
//! Frame lists are written as render farms write them. OpenCue (`FrameRange` in cuebot and pycue,
//! github.com/AcademySoftwareFoundation/OpenCue): `A`, `A-B`, `A-BxS` (every S-th frame), `A-ByS` (the
//! frames `A-BxS` leaves out: 1-10y3 is 2,3,5,6,8,9), `A-B:S` (an interleave: the same frames, in
//! another order), negative frames and steps (`-5--1`, `10-1x-1`), items joined by commas. Deadline
//! ("Frame List Formatting Options", Thinkbox): items joined by commas or spaces, `A:B` for `A-B`, a
//! step written `x`, `step`, `by`, `every` or, after `A:B`, `:` (`1:100:5`), and reverse ranges
//! (`100-1`, `100-1x5`), whose frames are never repeated. kelvin keeps its own `A..B` (ascending
//! only). Where the two farms differ, a list one of them refuses means what the other says: `10-1x3`
//! is Deadline's 10, 7, 4, 1 (OpenCue refuses a positive step downwards).

use std::path::{Path, PathBuf};
use std::str::FromStr;

/// The most frames one command renders.
const MAX_FRAMES: i64 = 1_000_000;

/// The frames to render, ascending, each once.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FrameRange {
    frames: Vec<i32>,
}

impl FrameRange {
    pub fn iter(&self) -> impl Iterator<Item = i32> + '_ {
        self.frames.iter().copied()
    }

    /// One frame only.
    pub fn is_single(&self) -> bool {
        self.frames.len() == 1
    }

    /// Whether `frame` is one of the frames.
    pub fn contains(&self, frame: i32) -> bool {
        self.frames.binary_search(&frame).is_ok()
    }
}

impl FromStr for FrameRange {
    type Err = String;

    /// A farm's frame list (see the module's comment). The frames are rendered in ascending order,
    /// each once, whatever order the list gives them in.
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = |why: &str| {
            format!("'{s}': {why} (frames are like 7, 0..47, 1-100, 1-100x2, 1-10y3, 1-10:3, -5--1 or 1,5,10-20)")
        };
        let mut frames = Vec::new();
        for item in s.split([',', ' ', '\t']).filter(|i| !i.is_empty()) {
            let (first, last, step) = parse_item(item).map_err(|e| bad(&e))?;
            // Counted before any frame is listed, so that a huge list fails at once.
            let span = match step {
                Some((Step::Every, by)) if by != 0 => (last - first).abs() / by.abs() + 1,
                _ => (last - first).abs() + 1,
            };
            if span > MAX_FRAMES || frames.len() as i64 + span > MAX_FRAMES {
                return Err(bad(&format!("more than {MAX_FRAMES} frames")));
            }
            let before = frames.len();
            frames.extend(item_frames(first, last, step).map_err(|e| bad(&format!("{item}: {e}")))?);
            if frames.len() == before {
                return Err(bad(&format!("{item} has no frames")));
            }
        }
        if frames.is_empty() {
            return Err(bad("no frames"));
        }
        frames.sort_unstable();
        frames.dedup();
        Ok(Self { frames: frames.into_iter().map(|f| f as i32).collect() })
    }
}

/// A farm task's frame list (`kelvin batch --frames`): any list but an interleave, whose `A-B:S`
/// Open Job Description (Deadline Cloud's task chunks) writes for a step, so that a task meant for
/// every S-th frame would render them all.
pub fn task_frames(s: &str) -> Result<FrameRange, String> {
    for item in s.split([',', ' ', '\t']).filter(|i| !i.is_empty()) {
        if let Ok((_, _, Some((Step::Interleave, step)))) = parse_item(item) {
            return Err(format!(
                "'{s}': {item} is OpenCue's interleave (every frame) but a step of {step} to Open Job \
                 Description: write the frames a task renders with 'x' or ','"
            ));
        }
    }
    s.parse()
}

/// How an item's step picks frames.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Step {
    /// Every S-th frame from A (`x`, Deadline's `step`, `by`, `every`, `:` after `A:B`).
    Every,
    /// The frames `Every` leaves out (OpenCue's `y`).
    Inverse,
    /// Every frame, in passes of halving steps (OpenCue's `:` after `A-B`).
    Interleave,
}

/// An item's first and last frame (equal for one frame) and its step, if any. Numbers are i32,
/// widened so that spans and steps cannot overflow.
fn parse_item(item: &str) -> Result<(i64, i64, Option<(Step, i64)>), String> {
    let mut rest = item;
    let first = number(&mut rest, item)?;
    if rest.is_empty() {
        return Ok((first, first, None));
    }
    let colon_range = rest.starts_with(':');
    let Some(after) = ["..", "-", ":"].iter().find_map(|sep| rest.strip_prefix(sep)) else {
        if step_marker(rest, false).is_some() {
            return Err("a step needs a range".into());
        }
        return Err(format!("{item:?}: {rest:?} is not a range or a step"));
    };
    let dots = rest.starts_with("..");
    rest = after;
    let last = number(&mut rest, item)?;
    if dots && last < first {
        return Err(format!("{last} is before {first}"));
    }
    if rest.is_empty() {
        return Ok((first, last, None));
    }
    let Some((kind, after)) = step_marker(rest, colon_range) else {
        return Err(format!("{item:?}: {rest:?} is not a step"));
    };
    rest = after;
    let step = number(&mut rest, item)?;
    if !rest.is_empty() {
        return Err(format!("{item:?}: {rest:?} after the step"));
    }
    Ok((first, last, Some((kind, step))))
}

/// The step marker `rest` starts with and what follows it. A `:` is Deadline's step after `A:B`,
/// OpenCue's interleave after `A-B`.
fn step_marker(rest: &str, colon_range: bool) -> Option<(Step, &str)> {
    let lower = rest.to_ascii_lowercase();
    let markers = [("x", Step::Every), ("step", Step::Every), ("by", Step::Every), ("every", Step::Every)];
    let marker = markers.into_iter().chain([("y", Step::Inverse)]).find(|(m, _)| lower.starts_with(m));
    match marker {
        Some((m, kind)) => Some((kind, &rest[m.len()..])),
        None => rest.strip_prefix(':').map(|r| (if colon_range { Step::Every } else { Step::Interleave }, r)),
    }
}

/// The frame number (or step) `rest` starts with, consumed: an optional '-' and digits, within i32.
fn number(rest: &mut &str, item: &str) -> Result<i64, String> {
    let sign = usize::from(rest.starts_with('-'));
    let end = sign + rest[sign..].bytes().take_while(u8::is_ascii_digit).count();
    let text = &rest[..end];
    let value = text.parse::<i32>().map_err(|_| match text {
        "" | "-" => format!("{item:?} is not a frame number"),
        _ => format!("{text} is not a frame number (beyond {})", i32::MAX),
    })?;
    *rest = &rest[end..];
    Ok(i64::from(value))
}

/// The frames of one item, checked as OpenCue checks them (a step of 0; a negative step upwards).
fn item_frames(first: i64, last: i64, step: Option<(Step, i64)>) -> Result<Vec<i64>, String> {
    let down = last < first;
    let all = || if down { (last..=first).rev().collect() } else { (first..=last).collect::<Vec<i64>>() };
    let Some((kind, step)) = step else { return Ok(all()) };
    if step == 0 {
        return Err("a step of 0".into());
    }
    if step < 0 && !down {
        return Err(format!("a negative step needs a range downwards ({first} to {last} goes up)"));
    }
    Ok(match kind {
        // From the first frame towards the last (downwards too with a positive step, as Deadline's 100-1x5).
        Step::Every if down => (last..=first).rev().step_by(step.unsigned_abs() as usize).collect(),
        Step::Every => (first..=last).step_by(step.unsigned_abs() as usize).collect(),
        Step::Inverse => all().into_iter().filter(|f| (f - first) % step != 0).collect(),
        // OpenCue's passes start at A, A+1, ... with steps S, S/2, ..., 1: the last pass covers all
        // but the frames the earlier ones start on, so together they are the range (and 10-1:1 none).
        Step::Interleave if step > 1 && down => return Err("a positive interleave needs a range upwards".into()),
        Step::Interleave if step == 1 && down => Vec::new(),
        Step::Interleave => all(),
    })
}

/// `pattern` with its file name's last run of '#' replaced by `frame`, zero-padded to the run's
/// length (out_####.exr: out_0007.exr; a negative frame's sign counts, as in printf's %04d and
/// Python's zfill: out_-007.exr), or an error if the name has no '#'.
pub fn frame_path(pattern: &Path, frame: i32) -> Result<PathBuf, String> {
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
pub fn frame_output(pattern: &Path, range: &FrameRange, frame: i32) -> Result<PathBuf, String> {
    match frame_path(pattern, frame) {
        Err(_) if range.is_single() => Ok(pattern.to_path_buf()),
        numbered => numbered,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(s: &str) -> Result<Vec<i32>, String> {
        s.parse::<FrameRange>().map(|r| r.iter().collect())
    }

    #[test]
    fn frame_ranges_and_numbered_names() {
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
        assert!(frames("0-4000000").unwrap_err().contains("more than"));
        assert!(frames("0-4000000000").unwrap_err().contains("not a frame number"));
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

    /// OpenCue's forms, with the examples of its FrameRange documentation, and Deadline's.
    #[test]
    fn opencue_and_deadline_frame_lists() {
        // Negative frames and ranges through zero.
        assert_eq!(frames("-2-2"), Ok(vec![-2, -1, 0, 1, 2]));
        assert_eq!(frames("-5--1"), Ok(vec![-5, -4, -3, -2, -1]));
        assert_eq!(frames("-3"), Ok(vec![-3]));
        // OpenCue: 1-10x3 is 1, 4, 7, 10; 1-10y3 the rest; 1-10:5 every frame (1, 6, 2, 4, 8, 10, 3, ...).
        assert_eq!(frames("1-10x3"), Ok(vec![1, 4, 7, 10]));
        assert_eq!(frames("1-10y3"), Ok(vec![2, 3, 5, 6, 8, 9]));
        assert_eq!(frames("1-10:5"), Ok((1..=10).collect()));
        assert_eq!(frames("10-1x-1"), Ok((1..=10).collect()));
        assert_eq!(frames("10-1x-4"), Ok(vec![2, 6, 10]));
        assert_eq!(frames("-1--9y-4"), Ok(vec![-8, -7, -6, -4, -3, -2]));
        assert_eq!(frames("10-1:-3"), Ok((1..=10).collect()));
        assert!(frames("1-10x-2").unwrap_err().contains("negative step"), "OpenCue refuses it");
        assert!(frames("10-1:3").unwrap_err().contains("interleave"), "OpenCue refuses it");
        assert!(frames("1-10y1").unwrap_err().contains("has no frames"));
        assert!(frames("1-10y0").unwrap_err().contains("step of 0"));
        assert!(frames("1-10:0").unwrap_err().contains("step of 0"));
        // Deadline: spaces, ':' ranges and steps, the step's other names, reverse ranges.
        assert_eq!(frames("5 10 15,20"), Ok(vec![5, 10, 15, 20]));
        assert_eq!(frames("1:100:5").map(|f| (f.len(), f[1], f[19])), Ok((20, 6, 96)));
        for step in ["1-20x5", "1-20step5", "1-20by5", "1-20every5", "1:20:5", "1-20X5"] {
            assert_eq!(frames(step), Ok(vec![1, 6, 11, 16]), "{step}");
        }
        assert_eq!(frames("5-1"), Ok(vec![1, 2, 3, 4, 5]));
        assert_eq!(frames("100-1x30"), Ok(vec![10, 40, 70, 100]));
        assert_eq!(frames("5,5,5"), Ok(vec![5]), "never repeated");
        // Bad items say which and why.
        assert!(frames("1-5z2").unwrap_err().contains("\"z2\" is not a step"));
        assert!(frames("1-").unwrap_err().contains("not a frame number"));
        assert!(frames("1-5x2x3").unwrap_err().contains("after the step"));
        assert!(frames(" , ").unwrap_err().contains("no frames"));
        assert!(frames("-2147483648-2147483647").unwrap_err().contains("more than"));
    }

    #[test]
    fn a_task_refuses_an_interleave_that_open_job_description_reads_as_a_step() {
        assert!(task_frames("1-3,7-20:2").unwrap_err().contains("7-20:2 is OpenCue's interleave"));
        assert_eq!(task_frames("1:9:4").map(|r| r.iter().collect::<Vec<_>>()), Ok(vec![1, 5, 9]), "Deadline's step");
        assert_eq!(task_frames("-2-2x2").map(|r| r.iter().collect::<Vec<_>>()), Ok(vec![-2, 0, 2]));
    }

    #[test]
    fn negative_frames_are_numbered_with_their_sign() {
        assert_eq!(frame_path(Path::new("out_####.exr"), -7).unwrap(), Path::new("out_-007.exr"));
        assert_eq!(frame_path(Path::new("f#.exr"), -12).unwrap(), Path::new("f-12.exr"));
    }
}
