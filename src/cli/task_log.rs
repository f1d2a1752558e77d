//! What a farm's monitor reads of a task: progress as a bar on a terminal, and as lines when stderr
//! is not one (a task runner captures it, and indicatif draws nothing there); with `--log FILE` the
//! same lines, each flushed, appended to the file, so that `tail -f` follows the task and a retried
//! task adds to its history. A line starts with the UTC time:
//!
//! ```text
//! 2026-12-07T23:10:05Z progress 40%: [1/1] lamp frames 11-15 40%, 12.3 s
//! ```
//!
//! Deadline's progress handler can read `progress (\d+)%`, which counts the whole task.

use std::fs::File;
use std::io::{IsTerminal, Write};
use std::path::Path;
use std::time::{Instant, SystemTime, UNIX_EPOCH};

use indicatif::ProgressBar;

use super::CliError;

/// A progress line at least each this many percent of a job, and after this many seconds without one.
const LINE_PERCENT: u32 = 5;
const LINE_SECONDS: f64 = 30.0;

/// Where a task's lines go.
pub struct TaskLog {
    file: Option<File>,
    /// Lines on stderr too (it is not a terminal).
    lines_on_stderr: bool,
}

impl TaskLog {
    /// Lines on stderr when it is not a terminal, and appended to `path` (its folder created) if given.
    pub fn open(path: Option<&Path>) -> Result<Self, CliError> {
        let file = match path {
            None => None,
            Some(path) => {
                let what = || format!("--log {}", path.display());
                if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
                    std::fs::create_dir_all(dir).map_err(super::exit::io(what()))?;
                }
                let file = std::fs::OpenOptions::new().create(true).append(true).open(path);
                Some(file.map_err(super::exit::io(what()))?)
            }
        };
        Ok(Self { file, lines_on_stderr: !std::io::stderr().is_terminal() })
    }

    /// `text` as a line, after the time, in the log file and (not a terminal) on stderr.
    pub fn line(&self, text: &str) {
        let line = format!("{} {text}\n", utc(SystemTime::now()));
        if self.lines_on_stderr {
            eprint!("{line}");
        }
        self.to_file(&line);
    }

    /// `text` on stderr whatever it is (a message a person at a terminal needs too), and in the file.
    pub fn note(&self, text: &str) {
        eprintln!("{text}");
        self.to_file(&format!("{} {text}\n", utc(SystemTime::now())));
    }

    /// `text` as a line in the log file only (a message stderr gets in another form).
    pub fn to_file_only(&self, text: &str) {
        self.to_file(&format!("{} {text}\n", utc(SystemTime::now())));
    }

    fn to_file(&self, line: &str) {
        // One write per line, so that lines of concurrent writers do not interleave mid-line. A log
        // that cannot be written does not fail the render (a full disk fails its outputs, with the code).
        if let Some(mut file) = self.file.as_ref() {
            file.write_all(line.as_bytes()).and_then(|()| file.flush()).ok();
        }
    }

    /// The progress of job `k` (from 0) of `n`, named `label`: a bar on a terminal, else lines.
    pub fn job(&self, k: usize, n: usize, label: &str) -> JobProgress<'_> {
        let bar = (!self.lines_on_stderr).then(|| {
            let bar = super::render::progress_bar();
            bar.set_message(format!("[{}/{n}] {label} ", k + 1));
            bar
        });
        let now = Instant::now();
        let label = format!("[{}/{n}] {label}", k + 1);
        JobProgress { log: self, bar, label, k, n, start: now, last_line: now, last_percent: None }
    }
}

/// One job's progress, reported as it moves.
pub struct JobProgress<'a> {
    log: &'a TaskLog,
    bar: Option<ProgressBar>,
    label: String,
    k: usize,
    n: usize,
    start: Instant,
    last_line: Instant,
    last_percent: Option<u32>,
}

impl JobProgress<'_> {
    /// The job is `done` (0 to 1) finished: the bar moves, or a line is written at each `LINE_PERCENT`
    /// and after `LINE_SECONDS` without one.
    pub fn set(&mut self, done: f32) {
        if let Some(bar) = &self.bar {
            bar.set_position((done * 1000.0) as u64);
        }
        let percent = (done.clamp(0.0, 1.0) * 100.0) as u32;
        let step = percent / LINE_PERCENT;
        let due = self.last_percent.is_none_or(|p| step > p / LINE_PERCENT)
            || self.last_line.elapsed().as_secs_f64() >= LINE_SECONDS;
        if !due {
            return;
        }
        self.last_percent = Some(percent);
        self.last_line = Instant::now();
        let task = ((self.k as f32 + done.clamp(0.0, 1.0)) / self.n as f32 * 100.0) as u32;
        let secs = self.start.elapsed().as_secs_f64();
        self.log.line(&format!("progress {task}%: {} {percent}%, {secs:.1} s", self.label));
    }

    /// Clears the bar.
    pub fn finish(self) {
        if let Some(bar) = self.bar {
            bar.finish_and_clear();
        }
    }
}

/// `time` as ISO 8601 UTC to the second, e.g. 2026-12-07T23:10:05Z.
fn utc(time: SystemTime) -> String {
    let secs = time.duration_since(UNIX_EPOCH).map_or(0, |d| d.as_secs()) as i64;
    let (days, rest) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    // Days since 1970-01-01 to a civil date: Howard Hinnant's `civil_from_days`
    // (howardhinnant.github.io/date_algorithms.html), over 400-year eras from 0000-03-01.
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z", rest / 3600, rest / 60 % 60, rest % 60)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_times() {
        let at = |s: u64| utc(UNIX_EPOCH + std::time::Duration::from_secs(s));
        assert_eq!(at(0), "1970-01-01T00:00:00Z");
        // `date -u -d @1700000000`, a leap day, the turn of a century that is a leap year.
        assert_eq!(at(1_700_000_000), "2023-11-14T22:13:20Z");
        assert_eq!(at(1_709_208_000), "2024-02-29T12:00:00Z");
        assert_eq!(at(951_868_799), "2000-02-29T23:59:59Z");
        assert_eq!(at(951_868_800), "2000-03-01T00:00:00Z");
    }
}
