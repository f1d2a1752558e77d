//! The temporary file an output is written to before it is renamed onto its name
//! ([`super::film_io::write_file`]): `.<name>.<host>.<pid>.<random>.partial`, beside the output. On
//! storage that many machines share (NFS), two writers of one output never share a temporary (a
//! process id alone repeats across hosts, and a later rename would publish the other's half-written
//! bytes), and a later run can tell one that is being written from one a killed writer left
//! ([`abandoned`]).

use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::{Duration, SystemTime};

/// The suffix of every temporary.
pub const SUFFIX: &str = ".partial";

/// A temporary untouched this long is abandoned whoever wrote it: a writer writes its bytes in one go
/// (seconds; minutes on a slow network disk), and an hour dwarfs the clock skew between hosts.
pub const ABANDONED_AFTER: Duration = Duration::from_secs(3600);

/// This machine's name as temporaries carry it: the kernel's host name, with every character other
/// than a letter, digit or '-' (the '.' that separates the name's fields) made '_'.
pub fn this_host() -> &'static str {
    static HOST: OnceLock<String> = OnceLock::new();
    HOST.get_or_init(|| {
        let name = std::fs::read_to_string("/proc/sys/kernel/hostname")
            .ok()
            .or_else(|| std::env::var("HOSTNAME").ok())
            .or_else(|| std::env::var("COMPUTERNAME").ok())
            .unwrap_or_default();
        let name: String =
            name.trim().chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' { c } else { '_' }).collect();
        if name.is_empty() { "unknown-host".to_owned() } else { name }
    })
}

/// A temporary path for writing `path`, unique to this host, process and call.
pub fn temporary_path(path: &Path) -> PathBuf {
    use std::hash::{BuildHasher, Hasher};
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    // std's hasher keys are random per process and differ for each `RandomState`; the time guards
    // against a platform without a random source.
    let mut hasher = std::collections::hash_map::RandomState::new().build_hasher();
    hasher.write_u128(SystemTime::now().duration_since(SystemTime::UNIX_EPOCH).unwrap_or_default().as_nanos());
    let random = hasher.finish();
    path.with_file_name(format!(".{name}.{}.{}.{random:016x}{SUFFIX}", this_host(), std::process::id()))
}

/// Whether the temporary at `temp` was left by a writer that stopped: untouched for
/// [`ABANDONED_AFTER`], or written on this host by a process that no longer runs (known from /proc,
/// where there is one). A temporary of another host is only judged by its age: its process cannot
/// be seen from here. False for a file that is gone.
pub fn abandoned(temp: &Path) -> bool {
    let Ok(modified) = std::fs::metadata(temp).and_then(|m| m.modified()) else { return false };
    // A time in the future (another host's clock ahead) is not old.
    if SystemTime::now().duration_since(modified).is_ok_and(|age| age >= ABANDONED_AFTER) {
        return true;
    }
    let name = temp.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let mut fields = name.strip_suffix(SUFFIX).unwrap_or_default().rsplit('.');
    let (_random, pid, host) = (fields.next(), fields.next(), fields.next());
    let pid = pid.and_then(|p| p.parse::<u32>().ok());
    match pid {
        Some(pid) if host == Some(this_host()) && Path::new("/proc/self").exists() => {
            !Path::new(&format!("/proc/{pid}")).exists()
        }
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temporaries_name_host_and_process_and_differ_per_call() {
        let a = temporary_path(Path::new("out/room.exr"));
        let b = temporary_path(Path::new("out/room.exr"));
        assert_ne!(a, b);
        let name = a.file_name().unwrap().to_string_lossy().into_owned();
        let host_pid = format!(".room.exr.{}.{}.", this_host(), std::process::id());
        assert!(name.starts_with(&host_pid) && name.ends_with(SUFFIX), "{name}");
        assert_eq!(a.parent(), Some(Path::new("out")));
        assert!(!this_host().contains('.') && !this_host().is_empty());
    }
}
