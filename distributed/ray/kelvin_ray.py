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

Tasks whose worker or node dies are retried (--max-retries); a job whose tile fails in kelvin itself
(a bad scene, say) fails with kelvin's message and the other jobs go on. The exit code is 0 only if
every job succeeded or was already finished. The kelvin binary and the scenes must be at the same
paths on every node (as in one container image); tiles travel through Ray, not a shared disk.
Without --address a local Ray cluster is started for the run.
"""

import argparse
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time

import ray


def tile_grid(width, height, tiles):
    """Crops (x0, y0, x1, y1) of a cols x rows grid of about `tiles` tiles, as square as the image allows."""
    best = None
    for rows in range(1, tiles + 1):
        if tiles % rows:
            continue
        cols = tiles // rows
        # How far a tile is from square, in log ratio.
        score = abs(math.log((width / cols) / (height / rows)))
        if best is None or score < best[0]:
            best = (score, cols, rows)
    _, cols, rows = best
    cols, rows = min(cols, width), min(rows, height)
    xs = [i * width // cols for i in range(cols + 1)]
    ys = [j * height // rows for j in range(rows + 1)]
    return [(xs[i], ys[j], xs[i + 1], ys[j + 1]) for j in range(rows) for i in range(cols)]


class TileFailed(Exception):
    """kelvin itself refused or failed a tile: retrying would fail the same way."""


@ray.remote
def render_tile(kelvin, args, crop, threads, timeout):
    """Runs `kelvin render ARGS --crop ...` in a temporary folder; returns (EXR bytes, node, seconds,
    kelvin's CPU seconds)."""
    start, cpu = time.monotonic(), cpu_seconds()
    node = ray.get_runtime_context().get_node_id()
    crop_arg = ",".join(map(str, crop))
    with tempfile.TemporaryDirectory(prefix="kelvin-tile-") as tmp:
        out = os.path.join(tmp, "tile.exr")
        cmd = [kelvin, "render", *args, "--crop", crop_arg, "--threads", str(threads), "-o", out]
        try:
            run = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            raise TileFailed(f"tile {crop_arg}: kelvin render took over {timeout} s")
        except OSError as e:
            raise TileFailed(f"tile {crop_arg}: cannot run {kelvin}: {e}")
        if run.returncode != 0:
            lines = [l for l in run.stderr.splitlines() if l.strip()]
            raise TileFailed(f"tile {crop_arg}: {lines[-1] if lines else 'kelvin render failed'}")
        with open(out, "rb") as f:
            return f.read(), node, time.monotonic() - start, cpu_seconds() - cpu


@ray.remote
def bake_part(kelvin, args, part, parts, threads, timeout):
    """Runs `kelvin bake ARGS --part PART/PARTS` in a temporary folder; returns (part file bytes, node,
    seconds, kelvin's CPU seconds)."""
    start, cpu = time.monotonic(), cpu_seconds()
    node = ray.get_runtime_context().get_node_id()
    what = f"part {part}/{parts}"
    with tempfile.TemporaryDirectory(prefix="kelvin-bake-") as tmp:
        # A volume is written as .ktx2 (its parts beside it), lightmaps into a folder.
        out = os.path.join(tmp, "out.ktx2" if args[0] == "volume" else "out")
        cmd = [kelvin, "bake", *args, "--part", f"{part}/{parts}", "--threads", str(threads), "-o", out]
        try:
            run = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            raise TileFailed(f"{what}: kelvin bake took over {timeout} s")
        except OSError as e:
            raise TileFailed(f"{what}: cannot run {kelvin}: {e}")
        if run.returncode != 0:
            lines = [l for l in run.stderr.splitlines() if l.strip()]
            raise TileFailed(f"{what}: {lines[-1] if lines else 'kelvin bake failed'}")
        found = [os.path.join(d, f) for d, _, fs in os.walk(tmp) for f in fs if f.endswith(".kbake")]
        if len(found) != 1:
            raise TileFailed(f"{what}: kelvin bake wrote {len(found)} part files")
        with open(found[0], "rb") as f:
            return f.read(), node, time.monotonic() - start, cpu_seconds() - cpu


def cpu_seconds():
    """User and system CPU seconds of this process's finished children (a worker runs one task at a time)."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def plan(kelvin, manifest):
    run = subprocess.run([kelvin, "batch", manifest, "--plan"], capture_output=True, text=True, timeout=120)
    if run.returncode != 0:
        sys.exit(f"kelvin batch --plan {manifest}: {run.stderr.strip()}")
    return json.loads(run.stdout)["jobs"]


def cause(err):
    """The message of a task's failure, without Ray's traceback."""
    if isinstance(err, ray.exceptions.RayTaskError) and isinstance(err.cause, TileFailed):
        return str(err.cause)
    return f"{type(err).__name__}: {str(err).strip().splitlines()[-1] if str(err).strip() else ''}"


def merge(kelvin, job, tiles):
    """Writes the job's tiles to a local folder and joins them with `kelvin merge`; None or the error."""
    os.makedirs(os.path.dirname(job["output"]) or ".", exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="kelvin-merge-") as tmp:
        paths = []
        for i, data in enumerate(tiles):
            paths.append(os.path.join(tmp, f"tile{i:03}.exr"))
            with open(paths[-1], "wb") as f:
                f.write(data)
        # The job's exposure, so that the PNG preview is the one `kelvin render` writes.
        exposure = [] if job.get("exposure") is None else ["--exposure", repr(job["exposure"])]
        cmd = [kelvin, "merge", *paths, "-o", job["output"], *exposure]
        run = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        return None if run.returncode == 0 else f"kelvin merge: {run.stderr.strip()}"


def merge_bake(kelvin, job, parts):
    """Writes the bake's parts into its parts folder and joins them with `kelvin bake --merge`; None or the error."""
    folder = job["parts_dir"]
    os.makedirs(folder, exist_ok=True)
    n = len(parts)
    for k, data in enumerate(parts, 1):
        with open(os.path.join(folder, f"part-{k}-of-{n}.kbake"), "wb") as f:
            f.write(data)
    cmd = [kelvin, "bake", *job["args"], "--merge", "-o", job["output"]]
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    return None if run.returncode == 0 else f"kelvin bake --merge: {run.stderr.strip()}"


def run(opts):
    kelvin = os.path.abspath(opts.kelvin)
    jobs = plan(kelvin, opts.manifest)
    if opts.address:
        ray.init(address=opts.address, log_to_driver=False)
    else:
        ray.init(log_to_driver=False)
    start = time.monotonic()
    # Jobs are keyed by their place in the plan: the frames of one manifest job share its index.
    status = {}  # plan position -> ("rendered" | "skipped" | "FAILED", detail)
    pending = {}  # object ref -> (plan position, tile index)
    tiles = {}  # plan position -> [EXR bytes or None]
    for i, job in enumerate(jobs):
        if job["error"]:
            status[i] = ("FAILED", job["error"])
        elif job["done"] and not opts.force:
            status[i] = ("skipped", f"{job['output']} exists")
        elif job.get("command") == "bake":
            n = job["parts"]
            tiles[i] = [None] * n
            for k in range(n):
                task = bake_part.options(num_cpus=opts.threads, max_retries=opts.max_retries)
                ref = task.remote(kelvin, job["args"], k + 1, n, opts.threads, opts.task_timeout)
                pending[ref] = (i, k)
        else:
            # A job whose tiles would not merge into its image (ReSTIR's reuse) renders as one tile.
            if job.get("untileable"):
                print(f"{job['name']}: one tile: {job['untileable']}", flush=True)
            crops = tile_grid(job["width"], job["height"], 1 if job.get("untileable") else opts.tiles)
            tiles[i] = [None] * len(crops)
            for t, crop in enumerate(crops):
                task = render_tile.options(num_cpus=opts.threads, max_retries=opts.max_retries)
                ref = task.remote(kelvin, job["args"], crop, opts.threads, opts.task_timeout)
                pending[ref] = (i, t)
    total, done = len(pending), 0
    per_node = {}  # node id -> [tiles, task seconds]
    deadline = start + opts.timeout
    while pending:
        left = deadline - time.monotonic()
        if left <= 0:
            for ref, (i, _) in pending.items():
                ray.cancel(ref, force=True)
                status.setdefault(i, ("FAILED", f"timed out after {opts.timeout} s"))
            break
        ready, _ = ray.wait(list(pending), num_returns=1, timeout=min(left, 10))
        for ref in ready:
            i, t = pending.pop(ref)
            done += 1
            try:
                data, node, secs, cpu = ray.get(ref)
            except Exception as err:  # a task's failure is that job's, not the run's
                if i not in status:
                    status[i] = ("FAILED", f"job {i} ({jobs[i]['name']}): {cause(err)}")
                    # The job's other tiles are of no use now.
                    for other, (j, _) in list(pending.items()):
                        if j == i:
                            ray.cancel(other)
                            del pending[other]
                            done += 1
                continue
            tiles[i][t] = data
            stats = per_node.setdefault(node, [0, 0.0, 0.0])
            stats[0], stats[1], stats[2] = stats[0] + 1, stats[1] + secs, stats[2] + cpu
            name = jobs[i]["name"]
            have = sum(d is not None for d in tiles[i])
            print(f"[{time.monotonic() - start:6.1f} s] tiles {done}/{total}: {name} {have}/{len(tiles[i])}", flush=True)
            if have == len(tiles[i]) and i not in status:
                join = merge_bake if jobs[i].get("command") == "bake" else merge
                error = join(kelvin, jobs[i], tiles[i])
                status[i] = ("FAILED", f"job {i} ({name}): {error}") if error else ("rendered", jobs[i]["output"])
                tiles[i] = []  # the bytes are written; free them
    wall = time.monotonic() - start
    print(f"{'status':<9} {'job':<24} output / cause")
    for i, job in enumerate(jobs):
        state, detail = status.get(i, ("FAILED", "not finished"))
        print(f"{state:<9} {job['name']:<24} {detail}")
    counts = {s: sum(1 for v in status.values() if v[0] == s) for s in ("rendered", "skipped", "FAILED")}
    print(f"{len(jobs)} jobs: {counts['rendered']} rendered, {counts['skipped']} skipped, {counts['FAILED']} failed")
    print(f"{total} tiles in {wall:.2f} s")
    for node, (n, secs, cpu) in sorted(per_node.items()):
        print(f"node {node[:12]}: {n} tiles, {secs:.2f} s in tasks ({cpu:.2f} CPU s), {n / wall:.2f} tiles/s")
    if opts.summary:
        summary = {
            "wall_seconds": wall,
            "tiles": total,
            "jobs": {str(k): {"status": v[0], "detail": v[1]} for k, v in status.items()},
            "nodes": {k: {"tiles": v[0], "task_seconds": v[1], "cpu_seconds": v[2]} for k, v in per_node.items()},
        }
        with open(opts.summary, "w") as f:
            json.dump(summary, f, indent=2)
    return 1 if counts["FAILED"] else 0


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("manifest", help="kelvin batch manifest (JSON)")
    p.add_argument("--tiles", type=int, default=16, help="tiles per job (default 16)")
    p.add_argument("--address", help="Ray cluster to attach to (HOST:PORT or auto); a local one when absent")
    p.add_argument("--kelvin", default="kelvin", help="the kelvin binary, at this path on every node")
    p.add_argument("--threads", type=int, default=1, help="CPUs (and kelvin threads) per tile task")
    p.add_argument("--max-retries", type=int, default=3, help="retries of a tile whose worker or node died")
    p.add_argument("--task-timeout", type=float, default=1800, help="seconds one kelvin render may take")
    p.add_argument("--timeout", type=float, default=24 * 3600, help="seconds the whole run may take")
    p.add_argument("--force", action="store_true", help="render jobs whose output exists again")
    p.add_argument("--summary", help="write the outcome, per job and per node, as JSON here")
    opts = p.parse_args()
    if opts.tiles < 1:
        p.error("--tiles must be at least 1")
    if os.sep not in opts.kelvin:
        found = __import__("shutil").which(opts.kelvin)
        opts.kelvin = found or opts.kelvin
    sys.exit(run(opts))


if __name__ == "__main__":
    main()
