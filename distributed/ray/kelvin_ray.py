#!/usr/bin/env python3
"""Renders a kelvin batch manifest on a Ray cluster, each job split into tiles.

    python kelvin_ray.py MANIFEST [--tiles 16] [--address HOST:PORT] [--kelvin PATH]

Reads the jobs with `kelvin batch MANIFEST --plan` (so a job means what it means to `kelvin batch`),
splits each unfinished one into a grid of tiles, renders every tile as a Ray task that runs
`kelvin render ... --crop X0,Y0,X1,Y1` and returns the tile's EXR bytes through Ray's object store,
then joins each job's tiles with `kelvin merge`, which checks that they cover the image exactly once.
kelvin's random numbers are a function of the pixel, so the merged image is byte for byte the one
`kelvin render` writes on one machine.

Bake jobs (`"bake"` in the manifest) split into the parts the manifest gives: each part is a task that
runs `kelvin bake ... --part K/N` and returns the part's sums; `kelvin bake ... --merge` joins them into the
lightmaps (or volume) byte for byte as one `kelvin bake` writes them.

A chunk of frames (`"chunk"` in the manifest) is one task that renders its frames whole in one process
(`kelvin render --frames A,B,C`) and returns their files, written beside the job's output pattern.

Failures are sorted by kelvin's exit code (kelvin_exit.py; `kelvin --help`), never by its message. A task whose
kelvin failed for its node's sake (exit code 3: disk full, permission, read-only file system, out of memory; 130:
interrupted; killed by a signal, the OOM killer say; timed out; could not be executed, 126/127), or whose worker,
node or result was lost, is retried (--max-retries) on another node where one is alive: the driver pins the retry
away from every node the task failed on. A task that kelvin itself refuses (exit code 2: a bad scene, bad settings;
1; 101, a panic) fails its job at once with kelvin's message; the other jobs go on.

Every finished tile is written at once, durably, into a staging folder beside the job's output
(`OUTPUT.tiles/X0_Y0_X1_Y1.exr`; a bake's parts go to kelvin's parts folder as `part-K-of-N.kbake`), so a driver
restarted after a crash renders only the tiles that are missing. A staged piece is checked before it is trusted
(its header decodes and records this tile, this build and files the plan lists; a part's checksum matches): one that
is not is moved into `STAGING.quarantine/` with a `.why` file, and rendered again. The staging folder is removed
once merged; if the merge refuses the staged tiles (made for other settings), they are moved to the quarantine
folder too and the job reported failed, so that a rerun renders it fresh. A failed job keeps its staged pieces.

The driver's own kelvin commands (the plan, each merge) have timeouts too; a merge that times out, or fails with a
transient code, fails its job but keeps its staged pieces for a rerun (nothing is quarantined). The exit code is 0
only if every job succeeded or was already finished; 3 (kelvin's environment code) if the plan itself failed for a
reason of this machine (timed out, kelvin could not run), so that running the driver again may succeed. The kelvin binary and the scenes must be
at the same paths on every node (as in one container image); tiles travel through Ray, not a shared disk. Each task
checks first that its node's binary is the driver's and its scene and environment map are the ones planned (their
SHA-256, from the plan's `inputs`): a node that differs, or lacks one, is a node failure, retried elsewhere.
Without --address a local Ray cluster is started for the run.

Work goes out in waves, so that the head's memory does not grow with the manifest: at most --in-flight tasks are
submitted and not yet handled (default: two per task slot of the alive nodes), taken in plan order; a job is opened
(its pieces made, its staged ones checked) only when the window has room for it and fewer than --open-jobs are
open, and forgotten once merged. --task-logs DIR keeps every attempt of every task: its node, its outcome and
kelvin's stderr (progress lines, messages), in DIR/JOB/PIECE.log.
"""

import argparse
import json
import os
import re
import resource
import shutil
import sys
import tarfile
import time
from collections import deque

import ray
from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy

import kelvin_exit
import kelvin_staged
import kelvin_tasks
from kelvin_jobs import Job, Piece, pieces_of, remove_temporaries, tile_grid, write_durably  # noqa: F401 (tests)
from kelvin_tasks import TaskFault, TileFailed, Whereabouts, bake_part, digest, render_chunk, render_tile

# The tasks' code travels with them, so nodes need not have this folder on their path.
ray.cloudpickle.register_pickle_by_value(kelvin_exit)
ray.cloudpickle.register_pickle_by_value(kelvin_staged)
ray.cloudpickle.register_pickle_by_value(kelvin_tasks)

# How long one ray.wait may block: completions are handled in batches this often at most.
WAIT_SECONDS = 0.5
# With --in-flight 0: tasks in flight per task slot of the alive nodes (one running, one queued behind it, so that
# a slot never waits for the driver), and at least this many in all.
IN_FLIGHT_PER_SLOT, IN_FLIGHT_MIN = 2, 8
# How often the automatic window looks at the cluster again (nodes join and leave).
SLOTS_EVERY = 10.0
# Seconds the driver's own kelvin commands may take: `kelvin batch --plan` (it hashes every input), and a merge.
PLAN_TIMEOUT = 600
MERGE_TIMEOUT = 600


def plan(kelvin, manifest):
    """The manifest's jobs as kelvin plans them (frames expanded, outputs checked), so none is interpreted here.
    Exits if kelvin cannot plan: with code 3 for a transient failure (a timeout), else 1."""
    out, failure = kelvin_exit.run_local([kelvin, "batch", manifest, "--plan"], f"kelvin batch {manifest} --plan",
                                         PLAN_TIMEOUT)
    if failure:
        print(failure, file=sys.stderr)
        sys.exit(kelvin_exit.ENVIRONMENT if failure.transient else 1)
    return json.loads(out)["jobs"]


def classify(err):
    """(transient, message, node or None) of a task's failure. Transient failures are the node's (its kelvin
    killed or not executable, its worker, raylet or objects lost): another node may succeed. Anything the task
    raised otherwise is the job's: kelvin's refusal, or a bug that would repeat."""
    if isinstance(err, ray.exceptions.RayTaskError):
        if isinstance(err.cause, TaskFault):
            return True, str(err.cause), err.cause.node
        if isinstance(err.cause, TileFailed):
            return False, str(err.cause), None
        return False, f"{type(err.cause).__name__}: {err.cause}", None
    text = str(err).strip()
    return True, f"{type(err).__name__}: {text.splitlines()[-1] if text else ''}", None


def merge(kelvin, job):
    """Joins the job's staged tiles with `kelvin merge`; None or the kelvin_exit.Failure."""
    os.makedirs(os.path.dirname(job.entry["output"]) or ".", exist_ok=True)
    # The job's exposure, so that the PNG preview is the one `kelvin render` writes.
    exposure = [] if job.entry.get("exposure") is None else ["--exposure", repr(job.entry["exposure"])]
    cmd = [kelvin, "merge", *(p.path for p in job.pieces), "-o", job.entry["output"], *exposure]
    return kelvin_exit.run_local(cmd, "kelvin merge", MERGE_TIMEOUT)[1]


def unpack_chunk(job):
    """Writes the frames of a chunk's staged tar beside its output pattern, each durably; None or the
    kelvin_exit.Failure (transient if the driver's disk failed, not the tar)."""
    folder = os.path.dirname(job.entry["output"]) or "."
    os.makedirs(folder, exist_ok=True)
    try:
        with tarfile.open(job.pieces[0].path) as tar:
            for member in tar.getmembers():
                name = os.path.basename(member.name)
                write_durably(os.path.join(folder, name), tar.extractfile(member).read())
    except (OSError, tarfile.TarError) as e:
        return kelvin_exit.Failure(f"unpacking {job.pieces[0].path}: {e}", isinstance(e, OSError))
    return None


def merge_bake(kelvin, job):
    """Joins the bake's staged parts with `kelvin bake --merge` (which removes its parts folder); None or the
    kelvin_exit.Failure."""
    cmd = [kelvin, "bake", *job.entry["args"], "--merge", "-o", job.entry["output"]]
    return kelvin_exit.run_local(cmd, "kelvin bake --merge", MERGE_TIMEOUT)[1]


def check_threads(threads):
    """Refuses --threads that no alive node has CPUs for: Ray would keep such tasks waiting, silently."""
    cpus = [n["Resources"].get("CPU", 0) for n in ray.nodes() if n["Alive"]]
    if threads > max(cpus, default=0):
        sys.exit(f"--threads {threads}: no node of the cluster has {threads} CPUs (the largest has "
                 f"{max(cpus, default=0):g}); every task would wait for one forever")


class Farm:
    """The driver's state: the jobs, the tasks in flight, the retries, and the figures for the summary.

    Work is submitted in waves: at most `window` tasks are in flight (submitted and not yet handled), taken in plan
    order, and a job is opened (its staged pieces checked, its missing ones queued) only when the window has room
    for its pieces and fewer than --open-jobs jobs are open. So the head holds the results of at most `window`
    tasks, the task specifications of as many, and staged pieces of the open jobs only, however long the
    manifest; a finished job's pieces are forgotten."""

    def __init__(self, kelvin, jobs, opts):
        self.kelvin, self.opts = kelvin, opts
        self.build = digest(kelvin)
        self.jobs = [Job(i, entry) for i, entry in enumerate(jobs)]
        self.pending = {}  # object ref -> (piece, pinned node or None, attempt id)
        self.queue = deque()  # jobs not opened yet, in plan order
        self.open = set()  # jobs opened and not decided
        self.waiting = deque()  # pieces of open jobs not submitted yet, in order
        self.pinned = {}  # node -> tasks pinned there in flight, to spread retries
        self.per_node = {}  # node id -> [tiles, task seconds, CPU seconds]
        self.retry_log = []  # one entry per retry: task, node, cause
        self.handled = []  # attempts the tracker may forget
        self.tasks = self.done = self.resumed = self.todo = 0
        self.staged_now = 0  # staged pieces of the open jobs
        self.peak = {"in_flight": 0, "open_jobs": 0, "staged": 0}
        self.slots_at, self.auto_window = -SLOTS_EVERY, IN_FLIGHT_MIN
        self.start = time.monotonic()
        here = ray.get_runtime_context().get_node_id()
        # On the driver's node, which outlives the nodes whose tasks it tracks.
        self.tracker = Whereabouts.options(scheduling_strategy=NodeAffinitySchedulingStrategy(here, soft=False)).remote()

    # -- starting

    def plan_jobs(self):
        """Decides what each job needs: nothing (failed in the plan, or finished), or to be opened in its turn."""
        for i, job in enumerate(self.jobs):
            entry = job.entry
            if entry["error"]:
                job.status = ("FAILED", entry["error"])
                continue
            # Counted, and the staging folder named; the pieces themselves are made when the job opens.
            count = len(pieces_of(i, job, self.opts.tiles))
            if entry["done"] and not self.opts.force:
                job.status = ("skipped", f"{entry['output']} exists")
                # A driver killed between a merge and its clean-up leaves the staged pieces behind.
                shutil.rmtree(job.staging, ignore_errors=True)
                continue
            self.todo += count
            self.queue.append(job)

    def open_job(self, job):
        """Makes the job's pieces, keeps the sound staged ones and queues the others (merging at once if none
        is missing)."""
        job.pieces = pieces_of(job.index, job, self.opts.tiles)
        self.open.add(job.index)
        if job.entry.get("untileable") and not job.chunk:
            print(f"{job.name}: one tile: {job.entry['untileable']}", flush=True)
        remove_temporaries(job.staging)
        if job.bake:
            self.quarantine_other_splits(job)
        planned = job.entry.get("inputs", {})
        missing = [p for p in job.pieces if not p.staged(self.build, planned, job.staging)]
        job.have = len(job.pieces) - len(missing)
        self.resumed += job.have
        self.staged_now += job.have
        if job.have:
            print(f"{job.name}: {job.have} of {len(job.pieces)} staged in "
                  f"{job.staging}, not rendered again", flush=True)
        self.waiting.extend(missing)
        self.note_peaks()
        if not missing:
            self.finish(job)

    def window(self):
        """Tasks that may be in flight: --in-flight, or IN_FLIGHT_PER_SLOT per task slot of the alive nodes."""
        if self.opts.in_flight:
            return self.opts.in_flight
        if time.monotonic() - self.slots_at >= SLOTS_EVERY:
            self.slots_at = time.monotonic()
            slots = sum(int(n["Resources"].get("CPU", 0) // self.opts.threads) for n in ray.nodes() if n["Alive"])
            self.auto_window = max(IN_FLIGHT_MIN, IN_FLIGHT_PER_SLOT * slots)
        return self.auto_window

    def fill(self):
        """Submits the next pieces, in plan order, while the window has room; opens the next job when the open
        ones have nothing left to submit and fewer than --open-jobs are open."""
        room = self.window()
        while len(self.pending) < room:
            if self.waiting:
                piece = self.waiting.popleft()
                if self.jobs[piece.job].status is None:  # not failed meanwhile
                    self.submit(piece)
                continue
            if not self.queue or (self.opts.open_jobs and len(self.open) >= self.opts.open_jobs):
                break
            self.open_job(self.queue.popleft())

    def note_peaks(self):
        for key, now in (("in_flight", len(self.pending)), ("open_jobs", len(self.open)), ("staged", self.staged_now)):
            self.peak[key] = max(self.peak[key], now)

    def quarantine_other_splits(self, job):
        """Moves aside the part files of another split of the bake (`kelvin bake --merge` reads every part file
        of the folder): a bake split anew resumes from its own parts only."""
        if not os.path.isdir(job.staging):
            return
        mine = {os.path.basename(p.path) for p in job.pieces}
        for name in sorted(os.listdir(job.staging)):
            if name.endswith(".kbake") and name not in mine:
                kelvin_staged.quarantine(job.staging, os.path.join(job.staging, name),
                                         f"a part of another split than {len(job.pieces)} parts")

    def submit(self, piece, node=None):
        """Starts a task for `piece`, pinned to `node` if given. Ray does not retry it itself (max_retries=0):
        the driver counts the retries and chooses their node."""
        job = self.jobs[piece.job]
        attempt = f"{piece.job}/{piece.index}/{piece.retries}"
        strategy = NodeAffinitySchedulingStrategy(node, soft=False) if node else "DEFAULT"
        o = self.opts
        # The binary this driver planned with, and the job's scene and environment map, each with its digest.
        inputs = {self.kelvin: self.build, **job.entry.get("inputs", {})}
        if job.bake:
            task = bake_part.options(num_cpus=o.threads, max_retries=0, scheduling_strategy=strategy)
            ref = task.remote(self.kelvin, inputs, job.entry["args"], *piece.spec, o.threads, o.task_timeout, self.tracker, attempt)
        elif job.chunk:
            task = render_chunk.options(num_cpus=o.threads, max_retries=0, scheduling_strategy=strategy)
            pattern = os.path.basename(job.entry["output"])
            ref = task.remote(self.kelvin, inputs, job.entry["args"], pattern, o.threads, o.task_timeout, self.tracker, attempt)
        else:
            task = render_tile.options(num_cpus=o.threads, max_retries=0, scheduling_strategy=strategy)
            ref = task.remote(self.kelvin, inputs, job.entry["args"], piece.spec, o.threads, o.task_timeout, self.tracker, attempt)
        self.pending[ref] = (piece, node, attempt)
        self.tasks += piece.retries == 0
        if node:
            self.pinned[node] = self.pinned.get(node, 0) + 1
        self.note_peaks()

    # -- the loop

    def run(self):
        """Handles finished tasks in batches and refills the window, until nothing is left or the time is up.
        One ray.wait per batch (back when a quarter of the window is done, or after WAIT_SECONDS), so the loop
        costs O(window) per batch, whatever the length of the manifest."""
        deadline = self.start + self.opts.timeout
        self.fill()
        while self.pending:
            left = deadline - time.monotonic()
            if left <= 0:
                self.time_out()
                break
            refs = list(self.pending)
            ready, _ = ray.wait(refs, num_returns=max(1, len(refs) // 4), timeout=min(left, WAIT_SECONDS))
            for ref in ready:
                self.handle(ref)
            if self.handled:  # one call per batch; the tracker would otherwise grow with every task of the run
                self.tracker.forget.remote(self.handled)
                self.handled = []
            self.fill()

    def handle(self, ref):
        """Stages a finished piece (merging its job when it was the last), or deals with its failure."""
        piece, pinned, attempt = self.pending.pop(ref)
        if pinned:
            self.pinned[pinned] -= 1
        job = self.jobs[piece.job]
        if job.status:  # the job failed already; its other tasks are of no use
            self.handled.append(attempt)
            return
        try:
            data, node, secs, cpu, log = ray.get(ref)
        except Exception as err:  # a task's failure is its job's, not the run's
            self.failed(piece, err, pinned, attempt)
            self.handled.append(attempt)
            return
        self.handled.append(attempt)
        self.keep_log(piece, node, f"done in {secs:.2f} s", log)
        try:
            write_durably(piece.path, data)
        except OSError as e:  # the driver's disk: no other node would help
            self.fail(job, f"job {job.index} ({job.name}): cannot stage {piece.what}: {e}")
            return
        self.done += 1
        stats = self.per_node.setdefault(node, [0, 0.0, 0.0])
        stats[0], stats[1], stats[2] = stats[0] + 1, stats[1] + secs, stats[2] + cpu
        job.have += 1
        self.staged_now += 1
        self.note_peaks()
        print(f"[{time.monotonic() - self.start:6.1f} s] tiles {self.done}/{self.todo - self.resumed}: {job.name} "
              f"{job.have}/{len(job.pieces)}", flush=True)
        if job.have == len(job.pieces):
            self.finish(job)

    def failed(self, piece, err, pinned, attempt):
        """Retries a transient failure away from the nodes it failed on; fails the job on a permanent one."""
        job = self.jobs[piece.job]
        transient, message, node = classify(err)
        node = node or self.where(attempt) or pinned
        log = self.keep_log(piece, node, f"failed: {message}", getattr(getattr(err, "cause", None), "log", ""))
        seen = f" (its log: {log})" if log else ""
        if not transient:
            self.fail(job, f"job {job.index} ({job.name}): {message}{seen}")
            return
        if node:
            piece.failed_on.add(node)
        if piece.retries >= self.opts.max_retries:
            self.fail(job, f"job {job.index} ({job.name}): {piece.what} failed {piece.retries + 1} times, last: "
                           f"{message}{seen}")
            return
        piece.retries += 1
        target = self.other_node(piece.failed_on)
        self.retry_log.append({"job": job.name, "task": piece.what, "retry": piece.retries, "failed_on": node,
                               "cause": message, "retried_on": target, "log": log})
        print(f"retry {piece.retries}/{self.opts.max_retries}: {job.name} {piece.what} failed on node "
              f"{(node or 'unknown')[:12]} ({message}); now on {'node ' + target[:12] if target else 'any node'}",
              flush=True)
        self.submit(piece, target)

    def keep_log(self, piece, node, outcome, text):
        """Appends an attempt of a piece to its task log (--task-logs DIR: DIR/JOB/PIECE.log, so a retried piece
        keeps every attempt's): a line with the time, the attempt, its node and outcome, then kelvin's stderr (its
        progress lines and messages). Returns the file, or None without --task-logs or if it cannot be written
        (a log never fails a task)."""
        if not self.opts.task_logs:
            return None
        safe = lambda name: re.sub(r"[^\w.,-]+", "_", name)
        path = os.path.join(self.opts.task_logs, safe(self.jobs[piece.job].name), safe(piece.what) + ".log")
        stamp = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
        try:
            os.makedirs(os.path.dirname(path), exist_ok=True)
            with open(path, "a") as f:
                f.write(f"{stamp} attempt {piece.retries + 1} on node {(node or 'unknown')[:12]}: {outcome}\n{text}")
        except OSError as e:
            print(f"task log {path}: {e}", file=sys.stderr, flush=True)
            return None
        return path

    def where(self, attempt):
        """The node an attempt started on, as the tracker heard it; None if it never started (or is unknown)."""
        try:
            return ray.get(self.tracker.node_of.remote(attempt), timeout=30)
        except Exception:
            return None

    def other_node(self, avoid):
        """An alive node with the CPUs for a task, not one of `avoid` (the one with the fewest pinned tasks in
        flight), or None if every such node is in `avoid`: then the task may run anywhere."""
        fit = [n["NodeID"] for n in ray.nodes()
               if n["Alive"] and n["Resources"].get("CPU", 0) >= self.opts.threads and n["NodeID"] not in avoid]
        return min(fit, key=lambda n: self.pinned.get(n, 0), default=None)

    def fail(self, job, detail):
        """Fails one job: cancels its tasks in flight (no other job's). Its staged pieces stay, whatever failed:
        a rerun renders only the missing ones, and checks those it finds (`Piece.staged`, then the merge's
        provenance check), so a piece that a fixed job would not use is moved aside then, not lost now."""
        staged = sum(os.path.exists(p.path) for p in job.pieces)
        job.status = ("FAILED", detail + (f" (its {staged} finished pieces stay staged in {job.staging})"
                                          if staged else ""))
        for ref, (piece, _, _) in list(self.pending.items()):
            if piece.job == job.index:
                ray.cancel(ref)
        self.close(job)

    def finish(self, job):
        """Merges a job whose pieces are all staged. A refused merge (pieces of other settings, say, that the
        staged check cannot see) moves them into the quarantine folder with merge's message, so that a rerun
        renders the job fresh and nothing is deleted. A merge that failed for a reason of this machine (timed
        out, a full disk) fails the job keeping its pieces staged: a rerun merges them."""
        if job.bake:
            self.quarantine_other_splits(job)
            error = merge_bake(self.kelvin, job)
        else:
            error = unpack_chunk(job) if job.chunk else merge(self.kelvin, job)
        if error and error.transient:
            job.status = ("FAILED", f"job {job.index} ({job.name}): {error}; its staged pieces stay in "
                                    f"{job.staging} for a rerun")
            self.close(job)
            return
        if error:
            for piece in job.pieces:
                if os.path.exists(piece.path):
                    kelvin_staged.quarantine(job.staging, piece.path, f"{piece.what}: refused: {error}")
            job.status = ("FAILED", f"job {job.index} ({job.name}): {error}; its staged pieces are moved to "
                                    f"{job.staging.rstrip(os.sep)}.quarantine")
        else:
            job.status = ("rendered", job.entry["output"])
        shutil.rmtree(job.staging, ignore_errors=True)
        self.close(job)

    def close(self, job):
        """A decided job leaves the window: its pieces are forgotten (their files stay where finish or fail left
        them), so that the driver's memory does not grow with the finished jobs."""
        self.open.discard(job.index)
        self.staged_now -= job.have
        job.pieces = []

    def time_out(self):
        """Cancels what is left; jobs not decided (opened or not) fail, their staged pieces kept for a rerun."""
        for ref in self.pending:
            ray.cancel(ref, force=True)
        self.pending.clear()
        for job in self.jobs:
            job.status = job.status or ("FAILED", f"timed out after {self.opts.timeout} s (finished tiles stay staged)")

    # -- the outcome

    def report(self):
        wall = time.monotonic() - self.start
        print(f"{'status':<9} {'job':<24} output / cause")
        for job in self.jobs:
            state, detail = job.status or ("FAILED", "not finished")
            print(f"{state:<9} {job.name:<24} {detail}")
        states = [(job.status or ("FAILED",))[0] for job in self.jobs]
        counts = {s: states.count(s) for s in ("rendered", "skipped", "FAILED")}
        print(f"{len(self.jobs)} jobs: {counts['rendered']} rendered, {counts['skipped']} skipped, {counts['FAILED']} failed")
        print(f"{self.tasks} tiles in {wall:.2f} s ({self.resumed} staged before, {len(self.retry_log)} retries; at most "
              f"{self.peak['in_flight']} in flight, {self.peak['open_jobs']} jobs open, {self.peak['staged']} staged)")
        for node, (n, secs, cpu) in sorted(self.per_node.items()):
            print(f"node {node[:12]}: {n} tiles, {secs:.2f} s in tasks ({cpu:.2f} CPU s), {n / wall:.2f} tiles/s")
        if self.opts.summary:
            self.write_summary(wall)
        return 1 if counts["FAILED"] else 0

    def write_summary(self, wall):
        summary = {
            "wall_seconds": wall,
            "tiles": self.tasks,  # tasks started this run (first attempts), staged pieces not counted
            "resumed": self.resumed,  # pieces found staged by an earlier run
            "retries": len(self.retry_log),
            "retry_log": self.retry_log,
            "jobs": {str(i): {"status": s[0], "detail": s[1]} for i, job in enumerate(self.jobs)
                     for s in [job.status or ("FAILED", "not finished")]},
            "nodes": {k: {"tiles": v[0], "task_seconds": v[1], "cpu_seconds": v[2]} for k, v in self.per_node.items()},
            # The waves' bounds (0: none given) and the most the run held at once.
            "bounds": {"in_flight": self.opts.in_flight or self.auto_window, "open_jobs": self.opts.open_jobs},
            "peak": self.peak,
            # The driver process alone (not the merges it ran): its CPU seconds and peak resident memory.
            "driver_cpu_seconds": (lambda t: t.user + t.system)(os.times()),
            "driver_max_rss_kb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss,
        }
        with open(self.opts.summary, "w") as f:
            json.dump(summary, f, indent=2)


def run(opts):
    kelvin = os.path.abspath(opts.kelvin)
    jobs = plan(kelvin, opts.manifest)
    if opts.address:
        ray.init(address=opts.address, log_to_driver=False)
    else:
        ray.init(log_to_driver=False)
    check_threads(opts.threads)
    farm = Farm(kelvin, jobs, opts)
    farm.plan_jobs()
    farm.run()
    return farm.report()


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("manifest", help="kelvin batch manifest (JSON)")
    p.add_argument("--tiles", type=int, default=16, help="tiles per job (default 16)")
    p.add_argument("--address", help="Ray cluster to attach to (HOST:PORT or auto); a local one when absent")
    p.add_argument("--kelvin", default="kelvin", help="the kelvin binary, at this path on every node")
    p.add_argument("--threads", type=int, default=1, help="CPUs (and kelvin threads) per tile task")
    p.add_argument("--max-retries", type=int, default=3,
                   help="retries of a tile whose kelvin, worker or node failed (on another node if one is alive)")
    p.add_argument("--task-timeout", type=float, default=1800, help="seconds one kelvin render may take")
    p.add_argument("--timeout", type=float, default=24 * 3600, help="seconds the whole run may take")
    p.add_argument("--force", action="store_true", help="render jobs whose output exists again")
    p.add_argument("--summary", help="write the outcome, per job and per node, as JSON here")
    p.add_argument("--task-logs", metavar="DIR",
                   help="keep each task's log here (DIR/JOB/PIECE.log: every attempt, its node and outcome, kelvin's "
                        "stderr)")
    p.add_argument("--in-flight", type=int, default=0,
                   help=f"tasks in flight at most (default 0: {IN_FLIGHT_PER_SLOT} per task slot of the alive nodes, "
                        f"at least {IN_FLIGHT_MIN})")
    p.add_argument("--open-jobs", type=int, default=0,
                   help="jobs open at most (tasks submitted or pieces staged, not merged); default 0: as many as the "
                        "in-flight tasks need")
    opts = p.parse_args()
    if opts.tiles < 1:
        p.error("--tiles must be at least 1")
    if opts.threads < 1:
        p.error("--threads must be at least 1")
    if opts.in_flight < 0 or opts.open_jobs < 0:
        p.error("--in-flight and --open-jobs must be 0 (automatic) or more")
    if os.sep not in opts.kelvin:
        opts.kelvin = shutil.which(opts.kelvin) or opts.kelvin
    sys.exit(run(opts))


if __name__ == "__main__":
    main()
