//! kelvin's exit codes, in one place: what failed, so that a farm's driver can tell a job it must
//! not retry from a machine that failed it (`distributed/ray/kelvin_exit.py` reads the same codes).
//!
//! | code | meaning | a driver |
//! |---|---|---|
//! | 0 | success | |
//! | 1 | failed otherwise (`kelvin batch`: some of its jobs failed, each line says why) | does not retry |
//! | 2 | bad input or settings: a scene, map or manifest that does not load, an option out of range (clap's usage errors too) | does not retry: it fails anywhere |
//! | 3 | environment or I/O: disk full, file too large, permission denied, read-only file system, out of memory, a device or network error | retries, on another machine |
//! | 130 | interrupted (128 + SIGINT, as a shell reports it) | retries |
//! | 101 | a panic: a bug | does not retry |

use std::io::ErrorKind;

use kelvin::render::film_io::ImageIoError;
use kelvin::render::job::JobError;
use kelvin::scene::gltf::GltfError;
use kelvin::scene::image::ImageError;

/// What an error says about where the fault lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Exit {
    /// Failed otherwise (a batch with failed jobs).
    Failed = 1,
    /// Bad input or settings: permanent.
    Input = 2,
    /// The machine's environment or I/O: transient.
    Environment = 3,
    /// Interrupted: transient.
    Interrupted = 130,
}

/// The text `kelvin --help` ends with.
pub const HELP: &str = "Exit codes: 0 success; 1 failed otherwise (batch: some jobs failed); \
2 bad input or settings (permanent: retrying elsewhere fails the same way); \
3 environment or I/O (disk full, file too large, permission denied, read-only file system, out of memory: \
transient, worth retrying on another machine); 130 interrupted; 101 a panic (a bug).";

/// An I/O failure the CLI met itself, keeping the operating system's error kind for [`classify`].
#[derive(Debug)]
pub struct IoFailure {
    /// What was being read or written.
    pub what: String,
    pub error: std::io::Error,
}

impl std::fmt::Display for IoFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.what, self.error)
    }
}

impl std::error::Error for IoFailure {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.error)
    }
}

/// A `map_err` that keeps an I/O error's kind, naming `what`.
pub fn io(what: impl std::fmt::Display) -> impl FnOnce(std::io::Error) -> super::CliError {
    move |error| Box::new(IoFailure { what: what.to_string(), error })
}

/// The code of an I/O error's kind: a file or folder the user named that does not exist is bad
/// input; everything else the machine's.
pub fn of_kind(kind: ErrorKind) -> Exit {
    match kind {
        ErrorKind::NotFound | ErrorKind::InvalidInput | ErrorKind::InvalidData | ErrorKind::IsADirectory => Exit::Input,
        ErrorKind::Interrupted => Exit::Interrupted,
        _ => Exit::Environment,
    }
}

/// The exit code of `error`, from its type (never from its text).
pub fn classify(error: &(dyn std::error::Error + 'static)) -> Exit {
    if let Some(e) = error.downcast_ref::<IoFailure>() {
        return of_kind(e.error.kind());
    }
    if let Some(e) = error.downcast_ref::<std::io::Error>() {
        return of_kind(e.kind());
    }
    if let Some(e) = error.downcast_ref::<ImageIoError>() {
        return match e {
            ImageIoError::Io { kind, .. } => of_kind(*kind),
            _ => Exit::Input,
        };
    }
    if let Some(e) = error.downcast_ref::<JobError>() {
        return match e {
            JobError::Invalid(_) => Exit::Input,
            JobError::Gltf(g) => classify(g),
            JobError::Image(i) => classify(i),
        };
    }
    // Reading an input that exists but cannot be read (EIO, permission) is the machine's fault.
    if let Some(GltfError::Io { .. }) = error.downcast_ref::<GltfError>() {
        return Exit::Environment;
    }
    if let Some(ImageError::Io { .. }) = error.downcast_ref::<ImageError>() {
        return Exit::Environment;
    }
    if error.downcast_ref::<clap::Error>().is_some() || error.downcast_ref::<GltfError>().is_some() {
        return Exit::Input;
    }
    if let Some(kelvin::bake::BakeError::Write(e)) = error.downcast_ref::<kelvin::bake::BakeError>() {
        return classify(e);
    }
    if error.downcast_ref::<ImageError>().is_some() || error.downcast_ref::<kelvin::bake::BakeError>().is_some() {
        return Exit::Input;
    }
    if let Some(e) = error.downcast_ref::<Coded>() {
        return e.exit;
    }
    // Messages the CLI formats itself are about its arguments and inputs.
    Exit::Input
}

/// An error with its exit code decided where it was made (`kelvin batch`'s summary).
#[derive(Debug)]
pub struct Coded {
    pub exit: Exit,
    pub message: String,
}

impl std::fmt::Display for Coded {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Coded {}
