"""kelvin's exit codes (src/cli/exit.rs; `kelvin --help` lists them) and what the Ray driver does with each: the one
place that reads them, so that a failure is classified by its code, never by the text kelvin printed.

No Ray here: the classification is tested alone (test_exit_codes.py) and sent to the workers by value. `run_local`
runs the driver's own kelvin commands (the plan, the merges) and sorts their failures the same way.
"""

import signal
import subprocess

SUCCESS = 0
FAILED = 1  # failed otherwise (`kelvin batch`: some of its jobs failed)
INPUT = 2  # bad input or settings (clap's usage errors too): fails the same way on any node
ENVIRONMENT = 3  # environment or I/O: disk full, file too large, permission, read-only file system, out of memory
INTERRUPTED = 130  # 128 + SIGINT
PANIC = 101  # Rust's exit code for a panic: a bug, which repeats anywhere
NOT_EXECUTABLE, NOT_FOUND = 126, 127  # the shell's codes for a binary that cannot run or is missing

# Codes that are the node's fault: worth retrying on another node.
TRANSIENT = {ENVIRONMENT, INTERRUPTED, NOT_EXECUTABLE, NOT_FOUND}

MEANING = {
    FAILED: "failed",
    INPUT: "bad input or settings",
    ENVIRONMENT: "environment or I/O failure",
    INTERRUPTED: "interrupted",
    PANIC: "panicked (a bug)",
    NOT_EXECUTABLE: "could not be executed",
    NOT_FOUND: "not found",
}


def is_transient(returncode):
    """Whether a kelvin that ended with `returncode` (subprocess's: negative for a signal) failed for a reason of
    its node: killed by a signal (the OOM killer, say), interrupted, or an environment or I/O failure."""
    return returncode < 0 or returncode in TRANSIENT


def describe(returncode):
    """What the code means, for messages."""
    if returncode < 0:
        return f"killed by {signal.Signals(-returncode).name}"
    return f"exit code {returncode}: {MEANING.get(returncode, 'unknown failure')}"


class Failure:
    """Why a kelvin command of the driver's failed, and whether the cause is transient: the machine's (a timeout,
    a binary that cannot start, an environment or I/O code), so that running it again may succeed."""

    def __init__(self, message, transient):
        self.message, self.transient = message, transient

    def __str__(self):
        return self.message


def run_local(cmd, what, timeout):
    """Runs `cmd` here with `timeout` seconds: (stdout, None) on success, else (stdout or "", Failure). A timeout
    is transient, like a binary that cannot be run: it says nothing about the job."""
    try:
        run = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return "", Failure(f"{what}: timed out after {timeout:g} s", True)
    except OSError as e:
        return "", Failure(f"{what}: cannot run {cmd[0]}: {e.strerror}", True)
    if run.returncode == 0:
        return run.stdout, None
    return run.stdout, Failure(f"{what}: kelvin {describe(run.returncode)}: {run.stderr.strip()}",
                               is_transient(run.returncode))
