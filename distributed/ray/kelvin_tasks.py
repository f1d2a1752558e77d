"""What runs on the nodes for kelvin_ray.py: one Ray task per tile, bake part or chunk of frames, each running one
kelvin command in a temporary folder and returning its files' bytes, and the failures they raise.

Before and after its kelvin runs, a task checks that its node holds the files the driver planned with (the kelvin
binary, the job's scene and environment map) with the same SHA-256: a node with another build or another copy of a
scene would render tiles that merge with seams, and a file replaced while kelvin read it gives a tile of neither.
A node that differs raises TaskFault, so the tile is retried elsewhere. (`kelvin merge` checks the tiles'
provenance again: the last word on what merges.)

The driver sends this module's code to the workers by value (ray.cloudpickle.register_pickle_by_value), so nodes
need neither this file nor the driver's folder on their path.
"""

import ctypes
import hashlib
import io
import os
import resource
import signal
import subprocess
import sys
import tarfile
import tempfile
import time

import ray

import kelvin_exit


# The most of a kelvin's stderr a task sends back (its end): progress lines are a few kB, a runaway log is cut.
LOG_BYTES = 64 << 10


class TileFailed(Exception):
    """kelvin itself refused or failed a tile (bad input or settings, a bug): retrying would fail the same way,
    anywhere. Carries kelvin's stderr (`log`) for the driver's task logs."""

    def __init__(self, message, log=""):
        super().__init__(message, log)
        self.message, self.log = message, log

    def __str__(self):
        return self.message


class TaskFault(Exception):
    """The tile failed for a reason of its node, not of the job (kelvin killed, interrupted, timed out or not
    executable, an environment or I/O failure such as a full disk, or the node's binary, scene or map not the
    planned file): worth retrying elsewhere. Carries the node so that the driver can avoid it, and kelvin's
    stderr (`log`, empty if it never ran)."""

    def __init__(self, node, message, log=""):
        super().__init__(node, message, log)
        self.node, self.message, self.log = node, message, log

    def __str__(self):
        return self.message


@ray.remote(num_cpus=0)
class Whereabouts:
    """Which node each task attempt started on. A task whose worker or node dies cannot say where it ran, and
    Ray's errors for it (WorkerCrashedError, NodeDiedError) do not name the node; the driver asks here."""

    def __init__(self):
        self.nodes = {}

    def started(self, attempt, node):
        self.nodes[attempt] = node

    def node_of(self, attempt):
        return self.nodes.get(attempt)

    def forget(self, attempts):
        """Drops handled attempts, so that the actor holds those in flight only, however many tasks a run has."""
        for attempt in attempts:
            self.nodes.pop(attempt, None)


def die_with_parent():
    """Runs in the kelvin child before exec: the kernel kills kelvin when its worker dies, so that a killed
    worker (or node) does not leave an orphan render eating a CPU that its retry needs."""
    PR_SET_PDEATHSIG = 1
    ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL)


def run_kelvin(cmd, what, timeout, node):
    """Runs one kelvin command and returns its stderr (the end of it); raises TaskFault for failures of the node
    and TileFailed for kelvin's own, told apart by kelvin's exit code alone (kelvin_exit)."""
    preexec = die_with_parent if sys.platform.startswith("linux") else None
    try:
        run = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, preexec_fn=preexec)
    except subprocess.TimeoutExpired as e:
        raise TaskFault(node, f"{what}: kelvin took over {timeout} s", tail(e.stderr))
    except OSError as e:
        raise TaskFault(node, f"{what}: cannot run {cmd[0]}: {e}")
    check_exit(run.returncode, run.stderr, what, node)
    return tail(run.stderr)


def tail(text):
    if isinstance(text, bytes):
        text = text.decode(errors="replace")
    return (text or "")[-LOG_BYTES:]


def check_exit(returncode, stderr, what, node):
    """Raises for a kelvin that failed: TaskFault for a code that is the node's fault (a signal, interrupted, an
    environment or I/O failure, not executable), TileFailed for the rest (bad input or settings, a panic: kelvin is
    deterministic, so they repeat anywhere). The message quotes kelvin's last line; the code alone decides."""
    if returncode == 0:
        return
    lines = [l for l in (stderr or "").splitlines() if l.strip()]
    last = lines[-1] if lines else "no message"
    message = f"{what}: kelvin {kelvin_exit.describe(returncode)}: {last}"
    if kelvin_exit.is_transient(returncode):
        raise TaskFault(node, message, tail(stderr))
    raise TileFailed(message, tail(stderr))


# The digests this worker process has computed, by (path, inode, size, modification time): a file is hashed once per
# worker, not once per task.
_digests = {}


def digest(path):
    """`sha256:` and the hex SHA-256 of the file at `path`, as kelvin writes digests (`inputs` of its plan)."""
    st = os.stat(path)
    key = (path, st.st_ino, st.st_size, st.st_mtime_ns)
    if key not in _digests:
        h = hashlib.sha256()
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
        _digests[key] = "sha256:" + h.hexdigest()
    return _digests[key]


def check_inputs(inputs, node, what):
    """Raises TaskFault unless this node holds every file of `inputs` (path -> digest) with that digest."""
    for path, want in inputs.items():
        try:
            have = digest(path)
        except OSError as e:
            raise TaskFault(node, f"{what}: {path}: {e.strerror} on this node")
        if have != want:
            raise TaskFault(node, f"{what}: {path} differs on this node ({have[:19]}..., the driver's "
                                  f"{want[:19]}...)")


def report_start(tracker, attempt):
    """Tells the tracker where this attempt runs (waiting for it, so a kill right after cannot lose it). Only a
    hint for choosing a retry's node: a tracker that cannot be reached does not fail the tile."""
    node = ray.get_runtime_context().get_node_id()
    try:
        ray.get(tracker.started.remote(attempt, node), timeout=60)
    except ray.exceptions.RayError:
        pass
    return node


def run_task(what, kelvin_args, collect, inputs, timeout, tracker, attempt):
    """What every task does: reports its node, checks the node's files, runs kelvin with `kelvin_args(tmp)` in a
    temporary folder, checks the files again (not changed while kelvin read them) and returns (`collect(tmp)`, the
    bytes to send back, node, seconds, kelvin's CPU seconds, kelvin's stderr)."""
    start, cpu = time.monotonic(), cpu_seconds()
    node = report_start(tracker, attempt)
    check_inputs(inputs, node, what)
    try:
        with tempfile.TemporaryDirectory(prefix="kelvin-task-") as tmp:
            log = run_kelvin(kelvin_args(tmp), what, timeout, node)
            check_inputs(inputs, node, what)
            return collect(tmp), node, time.monotonic() - start, cpu_seconds() - cpu, log
    except OSError as e:  # the node's temporary disk, not the job
        raise TaskFault(node, f"{what}: {e}")


def read(path):
    with open(path, "rb") as f:
        return f.read()


@ray.remote
def render_tile(kelvin, inputs, args, crop, threads, timeout, tracker, attempt):
    """`kelvin render ARGS --crop ...`; returns the tile's EXR bytes (with `run_task`'s figures)."""
    crop_arg = ",".join(map(str, crop))
    cmd = lambda tmp: [kelvin, "render", *args, "--crop", crop_arg, "--threads", str(threads), "-o",
                       os.path.join(tmp, "tile.exr")]
    return run_task(f"tile {crop_arg}", cmd, lambda tmp: read(os.path.join(tmp, "tile.exr")), inputs, timeout,
                    tracker, attempt)


@ray.remote
def bake_part(kelvin, inputs, args, part, parts, threads, timeout, tracker, attempt):
    """`kelvin bake ARGS --part PART/PARTS`; returns the part file's bytes (with `run_task`'s figures)."""
    what = f"part {part}/{parts}"
    # A volume is written as .ktx2 (its parts beside it), lightmaps into a folder.
    cmd = lambda tmp: [kelvin, "bake", *args, "--part", f"{part}/{parts}", "--threads", str(threads), "-o",
                       os.path.join(tmp, "out.ktx2" if args[0] == "volume" else "out")]

    def collect(tmp):
        found = [os.path.join(d, f) for d, _, fs in os.walk(tmp) for f in fs if f.endswith(".kbake")]
        if len(found) != 1:
            raise TileFailed(f"{what}: kelvin bake wrote {len(found)} part files")
        return read(found[0])

    return run_task(what, cmd, collect, inputs, timeout, tracker, attempt)


@ray.remote
def render_chunk(kelvin, inputs, args, pattern, threads, timeout, tracker, attempt):
    """`kelvin render ARGS` for a chunk of frames (whole frames, one process); returns a tar of every file it
    wrote, named as the job's output pattern numbers them (with `run_task`'s figures)."""
    cmd = lambda tmp: [kelvin, "render", *args, "--threads", str(threads), "-o", os.path.join(tmp, pattern)]

    def collect(tmp):
        packed = io.BytesIO()
        with tarfile.open(fileobj=packed, mode="w") as tar:
            for name in sorted(os.listdir(tmp)):
                tar.add(os.path.join(tmp, name), arcname=name)
        return packed.getvalue()

    return run_task(f"frames {args[args.index('--frames') + 1]}", cmd, collect, inputs, timeout, tracker, attempt)


def cpu_seconds():
    """User and system CPU seconds of this process's finished children (a worker runs one task at a time)."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime
