#!/usr/bin/env python3
"""CI test of the Ray driver on a local two-node cluster (a head and a second worker node on this machine).

    python test_cluster.py [--kelvin target/debug/kelvin]

1. A manifest of 3 jobs (two scenes, both colour modes, an environment camera), one of 2 frames of an animated
   scene, a ReSTIR job with an exposure (rendered as one tile: its reuse does not tile), a lightmap bake in 5 parts,
   6 frames in two chunks of 3 (a task each, staged apart), and 2 bad ones (a missing scene, a bad size), split into 16 tiles each: every merged image and its PNG preview
   is byte for byte a plain `kelvin render`'s (every baked file a plain `kelvin bake`'s), both nodes rendered
   tiles, the bad jobs fail with kelvin's message and the exit code says so, without retries. --threads 2 (more
   than any node's CPUs) is refused at start.
2. The same good jobs again while the second node's worker processes are killed mid-run: the driver retries their
   tiles on the head and the images are still byte-identical.
3. The same jobs with a kelvin that dies on the second node (a wrapper that kills itself with SIGKILL for a render,
   exits 127 for a bake, when the second node's environment says so): every tile that ran there is retried on the
   head, the summary shows those retries, and each retried tile's task log (--task-logs) keeps every attempt. (Before it, and before 5, a task pinned to the second node must run
   there: a node that Ray has not recovered from section 2's kills in 60 s is replaced by a fresh one.)
4. The driver is killed (SIGKILL) once some tiles are staged, a tile of another seed is planted among one job's
   staged tiles, and the driver is run again: it renders only the missing tiles, the planted tile's job fails
   naming the differing settings and its staging folder is gone; a third run renders that job fresh.
5. The scene file changes while its job runs (as on a node that holds another copy): every later tile fails its
   input check on both nodes, the job fails after its retries and keeps its finished tiles staged; with the scene
   restored, a rerun renders only the missing tiles, byte-identical.
6. 12 jobs of 16 small tiles in waves (the automatic window of 8 tasks, --open-jobs 2): the tiles staged on disk,
   counted from outside, never exceed 2 jobs' worth, the tasks in flight the window; every output is byte-identical.
7. Last, as it leaves one node: the whole second node (raylet, workers, kelvin) is killed with SIGKILL mid-run;
   its tiles are retried on the head and every output is byte-identical.

Every wait is bounded. The cluster runs in its own temporary folder and is stopped at the end, also when a
check fails, by ending the processes that folder names (and their children): nothing else on the machine.
"""

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
BOX = os.path.join(REPO, "tests/data/gltf/bevy/CornellBox.glb")
LAMP = os.path.join(REPO, "tests/data/gltf/kelvin/animated_lamp.gltf")
sys.path.insert(0, HERE)
from kelvin_ray import tile_grid  # noqa: E402  (the driver's grid, to count the tiles of a job)
from local_cluster import SECOND_NODE_ENV, Cluster, check, processes  # noqa: E402
import farm_scale  # noqa: E402




def kelvin_plan(kelvin, manifest):
    run = subprocess.run([kelvin, "batch", manifest, "--plan"], capture_output=True, text=True, timeout=60)
    check(run.returncode == 0, run.stderr)
    return json.loads(run.stdout)["jobs"]


def png_of(exr):
    return os.path.splitext(exr)[0] + ".png"


def references(kelvin, jobs, folder):
    """A plain `kelvin render` of each job: the bytes of its EXR and of its PNG preview, by output path (for a
    bake, a plain `kelvin bake`: the bytes of every file it writes)."""
    refs = {}
    for i, job in enumerate(jobs):
        if len(job["frames"]) > 1:
            # A chunk: the frames one `kelvin render` of the chunk writes, under the output pattern's names.
            out = os.path.join(folder, f"ref{i}")
            os.makedirs(out)
            cmd = [kelvin, "render", *job["args"], "-o", os.path.join(out, os.path.basename(job["output"]))]
            run = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
            check(run.returncode == 0, run.stderr)
            for name in os.listdir(out):
                with open(os.path.join(out, name), "rb") as f:
                    refs[os.path.join(os.path.dirname(job["output"]), name)] = f.read()
            check(len(os.listdir(out)) == 2 * len(job["frames"]), f"{os.listdir(out)}")
            continue
        if job["command"] == "bake":
            out = os.path.join(folder, f"ref{i}")
            run = subprocess.run([kelvin, "bake", *job["args"], "-o", out], capture_output=True, text=True, timeout=120)
            check(run.returncode == 0, run.stderr)
            for name in os.listdir(out):
                with open(os.path.join(out, name), "rb") as f:
                    refs[os.path.join(job["output"], name)] = f.read()
            continue
        out = os.path.join(folder, f"ref{i}.exr")
        run = subprocess.run([kelvin, "render", *job["args"], "-o", out], capture_output=True, text=True, timeout=120)
        check(run.returncode == 0, run.stderr)
        for mine, theirs in ((out, job["output"]), (png_of(out), png_of(job["output"]))):
            with open(mine, "rb") as f:
                refs[theirs] = f.read()
    return refs


def same_images(refs):
    for output, want in refs.items():
        check(os.path.exists(output), f"{output}: not written")
        with open(output, "rb") as f:
            check(f.read() == want, f"{output}: differs from a plain kelvin render")


def pieces(job):
    """Where the driver stages each tile (or bake part) of a plan entry: the names are its documented layout."""
    if job["command"] == "bake":
        n = job["parts"]
        return [os.path.join(job["parts_dir"], f"part-{k}-of-{n}.kbake") for k in range(1, n + 1)]
    if len(job["frames"]) > 1:
        return [os.path.join(f"{job['output']}.chunk-{job['frames'][0]}-{job['frames'][-1]}", "frames.tar")]
    crops = tile_grid(job["width"], job["height"], 1 if job["untileable"] else 16)
    return [os.path.join(job["output"] + ".tiles", "_".join(map(str, c)) + ".exr") for c in crops]


class Section:
    """One run of the driver on the good jobs, in a folder of its own (outputs, summary, log)."""

    def __init__(self, ctx, name, kelvin=None):
        self.ctx, self.folder = ctx, os.path.join(ctx.work, name)
        os.makedirs(self.folder)
        self.manifest = os.path.join(self.folder, "jobs.json")
        with open(self.manifest, "w") as f:
            json.dump({"jobs": ctx.good}, f)
        self.refs = {os.path.join(self.folder, os.path.relpath(k, ctx.work)): v for k, v in ctx.refs.items()}
        self.summary_path = os.path.join(self.folder, "summary.json")
        self.kelvin = kelvin or ctx.kelvin
        self.started = time.monotonic()

    def command(self, *extra):
        cmd = [sys.executable, os.path.join(HERE, "kelvin_ray.py"), self.manifest, "--tiles", "16"]
        cmd += ["--kelvin", self.kelvin, "--address", self.ctx.cluster.address, "--summary", self.summary_path]
        return cmd + ["--timeout", "240", "--max-retries", "5", *extra]

    def run(self, *extra):
        """Runs the driver to its end; (exit code, output)."""
        run = subprocess.run(self.command(*extra), env=self.ctx.cluster.env, capture_output=True, text=True, timeout=300)
        return run.returncode, run.stdout + run.stderr

    def start(self, *extra):
        """Starts the driver, its output into a log file (a pipe nobody reads could fill and stall it)."""
        self.log = open(os.path.join(self.folder, "driver.log"), "w+")
        return subprocess.Popen(self.command(*extra), env=self.ctx.cluster.env, stdout=self.log, stderr=subprocess.STDOUT)

    def finish(self, proc, deadline):
        """Waits (bounded) for a started driver; (exit code, output)."""
        try:
            proc.wait(timeout=max(1, deadline - time.monotonic()))
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait(timeout=10)
        self.log.seek(0)
        return proc.returncode, self.log.read()

    def summary(self):
        with open(self.summary_path) as f:
            return json.load(f)

    def elapsed(self):
        return f"{time.monotonic() - self.started:.1f} s, total {time.monotonic() - self.ctx.started:.1f} s"


def show(out):
    """The driver's retries (the first few) and its report, without the per-tile progress lines."""
    lines = out.splitlines()
    retries = [l for l in lines if l.startswith("retry ")]
    report = next((k for k, l in enumerate(lines) if l.startswith("status ")), max(0, len(lines) - 20))
    shown = retries[:4] + ([f"... and {len(retries) - 4} more retries"] if len(retries) > 4 else [])
    shown += [l[:400] for l in lines[report:] if not l.startswith("[")]
    print("\n".join(shown), flush=True)


def retries_from_second(ctx, result, causes=None):
    """Checks that the run retried, every retry of a known node away from the second node to the head; returns
    the retries by cause kind."""
    log = result["retry_log"]
    check(result["retries"] == len(log) and log, f"no retries: {result}")
    for r in log:
        check(r["failed_on"] in (ctx.ids["second"], None), f"a retry of a tile that failed on the head: {r}")
        if r["failed_on"]:
            check(r["retried_on"] == ctx.ids["head"], f"retried elsewhere than the head: {r}")
        check(causes is None or any(c in r["cause"] for c in causes), f"unexpected cause: {r}")
    kinds = {}
    for r in log:
        kind = next((c for c in causes or [] if c in r["cause"]), r["cause"].split(":")[0])
        kinds[kind] = kinds.get(kind, 0) + 1
    return kinds


def section_jobs(ctx):
    """1. Good and bad jobs: byte-identity, both nodes used, clear failures; --threads 2 refused."""
    summary = os.path.join(ctx.work, "summary.json")
    cmd = [sys.executable, os.path.join(HERE, "kelvin_ray.py"), ctx.manifest, "--tiles", "16", "--kelvin", ctx.kelvin,
           "--address", ctx.cluster.address, "--summary", summary, "--timeout", "240", "--max-retries", "5"]
    started = time.monotonic()
    run = subprocess.run(cmd, env=ctx.cluster.env, capture_output=True, text=True, timeout=300)
    show(run.stdout + run.stderr[-2000:])
    check(run.returncode == 1, f"the bad jobs fail the run: exit code {run.returncode}")
    same_images(ctx.refs)
    with open(summary) as f:
        result = json.load(f)
    states = {int(k): v for k, v in result["jobs"].items()}
    n = ctx.n_good
    check([states[i]["status"] for i in range(n + 2)] == ["rendered"] * n + ["FAILED"] * 2, f"{states}")
    check("no/such/scene.glb: no such file" in states[n]["detail"], states[n]["detail"])
    check("'0x10'" in states[n + 1]["detail"], states[n + 1]["detail"])
    check(result["retries"] == 0, f"kelvin's own errors are not retried: {result['retry_log']}")
    check(len(result["nodes"]) == 2, f"tiles ran on both nodes: {result['nodes']}")
    check(sum(v["tiles"] for v in result["nodes"].values()) == ctx.tasks, f"{result['nodes']}")
    # No node has 2 CPUs: refused at once, not left waiting.
    run = subprocess.run(cmd + ["--threads", "2"], env=ctx.cluster.env, capture_output=True, text=True, timeout=120)
    check(run.returncode != 0 and "--threads 2: no node of the cluster has 2 CPUs" in run.stderr,
          f"--threads 2 on 1-CPU nodes: exit code {run.returncode}: {run.stderr[-2000:]}")
    print(f"1. 3 jobs and 2 frames x 16 tiles, a whole ReSTIR job, a bake of 5 parts and 2 chunks ({ctx.tasks} tasks) "
          f"byte-identical, PNGs "
          f"included; bad jobs failed clearly, not retried; --threads 2 refused "
          f"({time.monotonic() - started:.1f} s, total {time.monotonic() - ctx.started:.1f} s)", flush=True)


def section_killed_workers(ctx):
    """2. The second node's workers killed (twice) while they run tiles."""
    sec = Section(ctx, "workers")
    proc, kills, deadline = sec.start(), [], time.monotonic() + 300
    try:
        while proc.poll() is None and time.monotonic() < deadline and len(kills) < 2:
            victims = ctx.cluster.kill_second_mid_task(whole_node=False)
            if victims:
                kills.append(victims)
                print(f"killed the second node's workers {victims}", flush=True)
                time.sleep(2.0)
            time.sleep(0.05)
    finally:
        code, out = sec.finish(proc, deadline)
    show(out)
    check(kills, "no tile was seen running on the second node, so nothing was killed")
    check(code == 0, f"the run with killed workers failed: exit code {code}")
    same_images(sec.refs)
    kinds = retries_from_second(ctx, sec.summary())
    print(f"2. killed workers {len(kills)} times; retries on the head {kinds}; outputs still byte-identical "
          f"({sec.elapsed()})", flush=True)


def broken_kelvin(ctx):
    """A kelvin that dies on the second node: `exit 127` (cannot execute) for a bake and for the tiles of an
    image's left column (crop 0,...), killed by SIGKILL for the other tiles; elsewhere the real binary."""
    path = os.path.join(ctx.work, "kelvin-broken-on-second-node")
    with open(path, "w") as f:
        f.write(f'#!/bin/sh\nif [ -n "${SECOND_NODE_ENV}" ]; then\n'
                f'  if [ "$1" = bake ]; then echo "no kelvin on this node" >&2; exit 127; fi\n'
                f'  for a in "$@"; do case "$a" in 0,*) echo "no kelvin on this node" >&2; exit 127;; esac; done\n'
                f'  kill -9 $$\nfi\nexec {ctx.kelvin} "$@"\n')
    os.chmod(path, 0o755)
    return path


def second_node_back(ctx):
    """Waits (bounded) until the second node runs tasks again after section 2's kills; replaces it by a fresh
    node if Ray has not recovered it in 60 s, so that the next sections test the driver, not Ray's recovery."""
    started = time.monotonic()
    if ctx.cluster.runs_on_second(ctx.ids["second"], timeout=60):
        print(f"the second node runs tasks ({time.monotonic() - started:.1f} s)", flush=True)
        return
    ctx.cluster.restart_second()
    ctx.ids = ctx.cluster.node_ids()
    check(ctx.cluster.runs_on_second(ctx.ids["second"], timeout=60), "a fresh second node runs no task")
    print(f"the second node ran no task for 60 s: replaced it by {ctx.ids['second'][:12]} "
          f"({time.monotonic() - started:.1f} s)", flush=True)


def section_broken_binary(ctx):
    """3. kelvin dies on the second node: every tile that ran there is retried on the head."""
    second_node_back(ctx)
    sec = Section(ctx, "broken", kelvin=broken_kelvin(ctx))
    code, out = sec.run("--task-logs", os.path.join(sec.folder, "logs"))
    show(out)
    check(code == 0, f"the run with a broken second node failed: exit code {code}")
    same_images(sec.refs)
    result = sec.summary()
    kinds = retries_from_second(ctx, result, causes=["killed by SIGKILL", "exit code 127"])
    # Each retried tile's log keeps every attempt: the failed ones (with what the broken kelvin printed) and
    # the last, done, with kelvin's progress lines.
    for r in result["retry_log"]:
        with open(r["log"]) as f:
            log = f.read()
        check(f"on node {ctx.ids['second'][:12]}: failed: " in log, f"{r['log']}: {log}")
        check("exit code 127" not in r["cause"] or "no kelvin on this node" in log, f"{r['log']}: {log}")
        if r["task"].startswith("tile"):
            done = log[log.rindex(" attempt "):]
            check(f"on node {ctx.ids['head'][:12]}: done in " in done and "progress 100%" in done, f"{r['log']}: {log}")
    check(all(r["failed_on"] == ctx.ids["second"] for r in result["retry_log"]), "the failing node is known")
    check(set(result["nodes"]) == {ctx.ids["head"]}, f"tiles succeed on the head only: {result['nodes']}")
    check(result["nodes"][ctx.ids["head"]]["tiles"] == ctx.tasks, f"{result['nodes']}")
    check(len(kinds) == 2, f"both kinds of death retried: {kinds}")
    print(f"3. kelvin broken on the second node: {result['retries']} retries on the head {kinds}, each tile's "
          f"attempts in its task log; outputs byte-identical ({sec.elapsed()})", flush=True)


def staged(jobs):
    """Pieces already staged, by plan position, for the jobs not finished."""
    return {i: [p for p in pieces(job) if os.path.exists(p)] for i, job in enumerate(jobs) if not job["done"]}


def plant_foreign_tile(ctx, jobs, have):
    """Renders one missing tile of an unfinished render job with another seed into its staging folder, as if
    left by an older job; returns that job's plan position."""
    for i, job in enumerate(jobs):
        missing = [p for p in pieces(job) if p not in have.get(i, [])]
        if job["done"] or job["command"] != "render" or job["untileable"] or not missing:
            continue
        args = list(job["args"])
        if "--seed" in args:
            args[args.index("--seed") + 1] = "77"
        else:
            args += ["--seed", "77"]
        crop = os.path.splitext(os.path.basename(missing[0]))[0].replace("_", ",")
        os.makedirs(os.path.dirname(missing[0]), exist_ok=True)
        run = subprocess.run([ctx.kelvin, "render", *args, "--crop", crop, "-o", missing[0]],
                             capture_output=True, text=True, timeout=120)
        check(run.returncode == 0, run.stderr)
        return i
    raise AssertionError("no unfinished render job to plant a tile in")


def section_resume(ctx):
    """4. The driver killed and restarted: only missing tiles rendered; a foreign staged tile fails its job."""
    sec = Section(ctx, "resume")
    every = [pieces(job) for job in kelvin_plan(ctx.kelvin, sec.manifest)]
    proc, deadline = sec.start(), time.monotonic() + 300
    try:
        while proc.poll() is None and time.monotonic() < deadline:
            # Staged pieces of jobs not complete (a complete one is merging, and its pieces go): the driver opens
            # jobs in plan order, a few at a time. Preferably a bake part among them.
            have = [p for job in every for h in [[p for p in job if os.path.exists(p)]] if len(h) < len(job)
                    for p in h]
            if len(have) >= 8 or (len(have) >= 3 and any(p.endswith(".kbake") for p in have)):
                proc.send_signal(signal.SIGKILL)
                break
            time.sleep(0.1)
    finally:
        code, _ = sec.finish(proc, deadline)
    check(code == -signal.SIGKILL, f"the driver was killed mid-run: exit code {code} (it finished first?)")
    # A merge the killed driver had started (a kelvin child of its own) runs on: let it end before counting.
    merging = lambda: [p for p, (_, argv) in processes().items() if "--merge" in argv or "merge" in argv[1:2]
                       if any(sec.folder in a for a in argv)]
    settle = time.monotonic() + 60
    while merging() and time.monotonic() < settle:
        time.sleep(0.1)
    jobs = kelvin_plan(ctx.kelvin, sec.manifest)
    have = staged(jobs)
    total, before = sum(len(pieces(jobs[i])) for i in have), sum(map(len, have.values()))
    victim = plant_foreign_tile(ctx, jobs, have)
    parts = sum(p.endswith(".kbake") for ps in have.values() for p in ps)
    print(f"killed the driver with {before} tiles of {total} of the unfinished jobs staged ({parts} of them bake "
          f"parts); planted a tile of seed 77 in {jobs[victim]['name']}", flush=True)

    code, out = sec.run()
    show(out)
    result = sec.summary()
    rendered = result["tiles"]
    check(code == 1, f"the job with the foreign tile fails the run: exit code {code}")
    check(result["resumed"] == before + 1, f"staged tiles found: {result['resumed']}, want {before + 1}")
    check(result["tiles"] == total - before - 1, f"tiles rendered: {result['tiles']}, want {total - before - 1}")
    check(sum(n["tiles"] for n in result["nodes"].values()) == result["tiles"], f"{result['nodes']}")
    detail = result["jobs"][str(victim)]["detail"]
    check(result["jobs"][str(victim)]["status"] == "FAILED" and "settings" in detail, detail)
    check(not os.path.exists(jobs[victim]["output"] + ".tiles"), "the refused tiles leave the staging folder")
    quarantined = jobs[victim]["output"] + ".tiles.quarantine"
    kept = [n for n in os.listdir(quarantined) if n.endswith(".exr")] if os.path.isdir(quarantined) else []
    check(len(kept) == len(pieces(jobs[victim])) and all(os.path.exists(os.path.join(quarantined, n + ".why")) for n in kept),
          f"the refused tiles are moved aside with the reason, not deleted: {kept}")
    victim_out = jobs[victim]["output"]
    same_images({k: v for k, v in sec.refs.items() if k not in (victim_out, png_of(victim_out))})

    code, out = sec.run()
    show(out)
    result = sec.summary()
    check(code == 0, f"the third run failed: exit code {code}")
    check(result["resumed"] == 0 and result["tiles"] == len(pieces(jobs[victim])), f"{result}")
    same_images(sec.refs)
    leftovers = [d for d, _, _ in os.walk(sec.folder) if d.endswith(".tiles") or d.endswith("parts")]
    check(not leftovers, f"staging folders left: {leftovers}")
    print(f"4. driver killed with {before}/{total} tiles staged; the rerun rendered the {rendered} "
          f"missing ones only, failed the job with the foreign tile, a third run rendered it fresh; byte-identical "
          f"({sec.elapsed()})", flush=True)


def replace_file(path, source):
    """Gives `path` the contents of `source` at once (a new file renamed over it)."""
    shutil.copy(source, path + ".new")
    os.replace(path + ".new", path)


def section_changed_scene(ctx):
    """5. The scene changes under a running job: later tiles fail their input check everywhere; the job fails
    keeping its finished tiles, and a rerun with the scene restored renders only the missing ones."""
    sec = Section(ctx, "changed")
    scene = os.path.join(sec.folder, "box.glb")
    shutil.copy(BOX, scene)
    job = dict(ctx.good[1], scene=scene)
    with open(sec.manifest, "w") as f:
        json.dump({"jobs": [job]}, f)
    output = os.path.join(sec.folder, job["output"])
    tiles = output + ".tiles"
    staged_tiles = lambda: len([n for n in os.listdir(tiles) if n.endswith(".exr")]) if os.path.isdir(tiles) else 0
    proc, deadline, swapped = sec.start("--max-retries", "1"), time.monotonic() + 300, False
    try:
        while proc.poll() is None and time.monotonic() < deadline:
            if not swapped and staged_tiles() >= 3:
                replace_file(scene, LAMP)
                swapped = True
            time.sleep(0.05)
    finally:
        code, out = sec.finish(proc, deadline)
    show(out)
    check(swapped, "the job ended before 3 tiles were staged")
    check(code == 1, f"the job with a changed scene fails the run: exit code {code}")
    result, kept = sec.summary(), staged_tiles()
    detail = result["jobs"]["0"]["detail"]
    check("differs on this node" in detail and "stay staged" in detail, detail)
    check(kept >= 3, f"the finished tiles stay staged: {kept}")
    check(result["retry_log"] and all("differs on this node" in r["cause"] for r in result["retry_log"]),
          f"{result['retry_log']}")
    retries = len(result["retry_log"])
    replace_file(scene, BOX)
    code, out = sec.run()
    show(out)
    result = sec.summary()
    check(code == 0, f"the rerun with the scene restored failed: exit code {code}")
    check(result["resumed"] == kept and result["tiles"] == 16 - kept, f"{result}")
    same_images({k: v for k, v in sec.refs.items() if k in (output, png_of(output))})
    print(f"5. scene changed mid-run: {retries} retries failed the input check, the job failed "
          f"keeping {kept} tiles; the rerun rendered the {16 - kept} missing ones, byte-identical ({sec.elapsed()})",
          flush=True)


def section_waves(ctx):
    """6. Many small tasks in waves (the automatic window, at most 2 jobs open): the tiles staged on disk, counted
    from outside every half second, stay within 2 jobs' worth, the driver's tasks in flight within its window; every
    output is a plain render's bytes. Prints the head's memory and the cost per task."""
    folder = os.path.join(ctx.work, "waves")
    os.makedirs(folder)
    jobs, tiles = 12, 16
    manifest = farm_scale.manifest(folder, jobs)
    want = farm_scale.reference(ctx.kelvin, folder)
    started = time.monotonic()
    code, wall, summary, sampler = farm_scale.run_driver(
        ctx.cluster, ctx.kelvin, manifest, os.path.join(folder, "summary.json"), os.path.join(folder, "driver.log"),
        "--tiles", str(tiles), "--open-jobs", "2", timeout=300)
    check(code == 0, f"the waves run failed: exit code {code}")
    check(farm_scale.same_outputs(folder, want) == jobs, "every job written")
    f = farm_scale.figures(summary, sampler, slots=2)
    check(summary["tiles"] == jobs * tiles and f["bounds"]["in_flight"] == 8, f"{summary['tiles']}, {f['bounds']}")
    check(f["driver_peak"]["in_flight"] <= 8 and f["driver_peak"]["open_jobs"] <= 2, f"{f['driver_peak']}")
    check(f["staged_peak"] <= 2 * tiles and f["driver_peak"]["staged"] <= 2 * tiles,
          f"{f['staged_peak']} tiles staged on disk at once, {f['driver_peak']['staged']} by the driver's count")
    print(f"6. waves: {farm_scale.describe(f)}; byte-identical ({time.monotonic() - started:.1f} s, total "
          f"{time.monotonic() - ctx.started:.1f} s)", flush=True)


def section_node_death(ctx):
    """7. The whole second node killed mid-run: its tiles are retried on the head."""
    second_node_back(ctx)
    sec = Section(ctx, "node-death")
    proc, victims, deadline = sec.start(), [], time.monotonic() + 300
    try:
        while proc.poll() is None and time.monotonic() < deadline and not victims:
            # Once a quarter of the tiles are done, so that the second node has finished some and runs more.
            sec.log.seek(0)
            progress = sum(1 for l in sec.log if l.startswith("["))
            if progress >= 20:
                victims = ctx.cluster.kill_second_mid_task(whole_node=True)
            if victims:
                print(f"killed the second node: raylet and {len(victims) - 1} processes under it", flush=True)
            time.sleep(0.05)
    finally:
        code, out = sec.finish(proc, deadline)
    show(out)
    check(victims, "no tile was seen running on the second node, so it was not killed")
    check(code == 0, f"the run that lost a node failed: exit code {code}")
    same_images(sec.refs)
    result = sec.summary()
    kinds = retries_from_second(ctx, result)
    check(result["nodes"].get(ctx.ids["second"], {}).get("tiles"), f"the second node rendered before: {result['nodes']}")
    tiles = {("second" if k == ctx.ids["second"] else "head"): v["tiles"] for k, v in result["nodes"].items()}
    print(f"7. second node killed after {tiles['second']} tiles; retries on the head {kinds}; outputs byte-identical "
          f"({sec.elapsed()})", flush=True)


class Context:
    """What the sections share: the cluster, the binary, the good jobs and their reference outputs."""

    def __init__(self, kelvin, work, cluster):
        self.kelvin, self.work, self.cluster, self.started = kelvin, work, cluster, time.monotonic()
        self.good = [
            {"name": "room", "output": "out/room.exr", "size": "96x72", "spp": 128},
            {"name": "box-spectral", "scene": BOX,
             "output": "out/box.exr", "size": "80x80", "spp": 128, "settings": {"color": "spectral", "seed": 3}},
            {"name": "room-env-camera", "output": "out/env.exr", "size": "96x48", "spp": 128,
             "camera": {"environment_at": [0, 1, 0]}, "settings": {"light_sampler": "power"}},
            # Two frames of an animation: two jobs of 16 tiles.
            {"name": "lamp", "scene": LAMP,
             "output": "out/lamp_#.exr", "frames": "3..4", "fps": 4, "size": "48x32", "spp": 16},
            # ReSTIR's reuse does not tile: one task renders it whole; its exposure reaches the PNG.
            {"name": "room-restir", "output": "out/restir.exr", "size": "40x30", "spp": 8,
             "settings": {"light_sampler": "restir", "exposure": 1.5}},
            # Lightmaps baked in 5 parts on the cluster and merged.
            {"name": "box-lightmaps", "bake": "lightmaps", "scene": BOX,
             "output": "out/maps", "parts": 5, "settings": {"size": 24, "spp": 16, "seed": 2}},
            # Two chunks of 3 frames: each one task that renders its frames whole in one process.
            {"name": "lamp-chunk", "scene": LAMP,
             "output": "out/chunk_##.exr", "frames": "5-15x2", "chunk": 3, "fps": 4, "size": "48x32", "spp": 16},
        ]
        bad = [
            {"name": "missing-scene", "scene": "no/such/scene.glb", "output": "out/missing.exr"},
            {"name": "bad-size", "output": "out/bad.exr", "size": "0x10"},
        ]
        self.manifest = os.path.join(work, "jobs.json")
        with open(self.manifest, "w") as f:
            json.dump({"jobs": self.good + bad}, f)
        planned = kelvin_plan(kelvin, self.manifest)
        # The good jobs' plan entries (the frames and chunks of a job are entries of their own) and their tasks.
        self.n_good = len(planned) - len(bad)
        self.tasks = sum(len(pieces(job)) for job in planned[:self.n_good])
        self.refs = references(kelvin, planned[:self.n_good], work)
        self.ids = None


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--kelvin", default=os.environ.get("KELVIN_BIN", os.path.join(REPO, "target/debug/kelvin")))
    opts = p.parse_args()
    kelvin = os.path.abspath(opts.kelvin)
    check(os.access(kelvin, os.X_OK), f"{kelvin}: no kelvin binary (cargo build --bin kelvin)")
    ray_bin = os.path.join(os.path.dirname(sys.executable), "ray")
    check(os.access(ray_bin, os.X_OK), f"{ray_bin}: run from the venv of requirements.txt")
    started = time.monotonic()
    # Short: Ray's socket paths live under it and must fit in 107 bytes.
    work = tempfile.mkdtemp(prefix="kray-", dir="/tmp")
    cluster = Cluster(ray_bin, work)
    try:
        ctx = Context(kelvin, work, cluster)
        ctx.started = started
        cluster.start()
        ctx.ids = cluster.node_ids()
        print(f"cluster up at {cluster.address} in {time.monotonic() - started:.1f} s: head {ctx.ids['head'][:12]}, "
              f"second {ctx.ids['second'][:12]}", flush=True)
        section_jobs(ctx)
        section_killed_workers(ctx)
        section_broken_binary(ctx)
        section_resume(ctx)
        section_changed_scene(ctx)
        section_waves(ctx)
        section_node_death(ctx)  # last: the cluster has one node after it
    finally:
        cluster.stop()
        shutil.rmtree(work, ignore_errors=True)
    print(f"ok in {time.monotonic() - started:.1f} s")


if __name__ == "__main__":
    main()
