#!/usr/bin/env python3
"""Splitting overhead and scaling: one job as N tiles on local Ray clusters of 1, 2 and 3 nodes (1 CPU each,
one kelvin thread per tile) against one `kelvin render --threads 1` of the same image, alternated `--rounds`
times; checks that the images are byte-identical.

    python bench_cluster.py --kelvin target/release/kelvin [--size 480x270] [--spp 32] [--tiles 16] [--nodes 1,2,3]
        [--rounds 2] [--json-out FILE]
    python bench_cluster.py --kelvin target/release/kelvin --scale 625 --tiles 16 [--stub] [--nodes 2]
        [--driver-args "--in-flight 8"]

With --scale JOBS: the driver at farm scale (farm_scale.py), JOBS x --tiles small tasks (64x64 images of the default
scene at 1 spp) on one cluster of --nodes nodes, submitted in waves; checks every output against a plain render and
prints the tasks per second, the scheduling overhead per task, the head's CPU per task and its peak memory (driver,
GCS, raylet, tracker). --stub: the tasks copy tiles rendered beforehand, so they cost Ray's and the driver's work.

Per node count: the single render's wall and CPU seconds, the driver's tiles-and-merge wall time and the tiles'
CPU seconds; overhead per tile = (CPU of the tiles - CPU of the single render) / tiles; throughput = camera
samples per second of wall time (tiles and merge). The nodes share this machine's cores: with more nodes than
cores, throughput stops at the cores'.
"""

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time

import farm_scale
from kelvin_ray import tile_grid
from local_cluster import Cluster, check

HERE = os.path.dirname(os.path.abspath(__file__))


def children_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def single_render(opts, kelvin, out):
    """(wall s, CPU s) of one `kelvin render --threads 1`."""
    t, cpu = time.monotonic(), children_cpu()
    run = subprocess.run([kelvin, "render", "-o", out, "--size", opts.size, "--spp", str(opts.spp), "--threads", "1"],
                         capture_output=True, text=True, timeout=1200)
    check(run.returncode == 0, run.stderr)
    return time.monotonic() - t, children_cpu() - cpu


def tiled_render(opts, kelvin, cluster, manifest, work):
    """The driver's summary and its process's wall time."""
    summary = os.path.join(work, "summary.json")
    cmd = [sys.executable, os.path.join(HERE, "kelvin_ray.py"), manifest, "--kelvin", kelvin, "--force",
           "--tiles", str(opts.tiles), "--address", cluster.address, "--summary", summary]
    t = time.monotonic()
    run = subprocess.run(cmd, env=cluster.env, capture_output=True, text=True, timeout=1200)
    whole = time.monotonic() - t
    check(run.returncode == 0, run.stdout + run.stderr)
    with open(summary) as f:
        return json.load(f), whole


def scale(opts, kelvin):
    """One run of the driver on JOBS x --tiles small tasks; its figures, and the head's samples over time."""
    nodes = int(opts.nodes.split(",")[0])
    work = tempfile.mkdtemp(prefix="kray-scale-", dir="/tmp")
    cluster = Cluster(os.path.join(os.path.dirname(sys.executable), "ray"), work, workers=nodes - 1)
    try:
        manifest = farm_scale.manifest(work, opts.scale, size=opts.scale_size)
        want = farm_scale.reference(kelvin, work, size=opts.scale_size)
        if opts.stub:
            w, h = map(int, opts.scale_size.split("x"))
            kelvin = farm_scale.stub_kelvin(kelvin, work, tile_grid(w, h, opts.tiles), size=opts.scale_size)
        cluster.start()
        code, wall, summary, sampler = farm_scale.run_driver(
            cluster, kelvin, manifest, os.path.join(work, "summary.json"), os.path.join(work, "driver.log"),
            "--tiles", str(opts.tiles), *opts.driver_args.split())
        if code != 0:
            with open(os.path.join(work, "driver.log")) as log:
                check(False, f"the driver failed (exit code {code}):\n{log.read()[-3000:]}")
        same = farm_scale.same_outputs(work, want)
        check(same == opts.scale, f"{same} of {opts.scale} outputs written")
        f = farm_scale.figures(summary, sampler, slots=nodes)
        f["driver_process_wall_s"], f["load"], f["stub"] = wall, os.getloadavg()[0], opts.stub
        print(f"{nodes} node(s), {opts.scale} jobs x {opts.tiles} tiles{' (stub kelvin)' if opts.stub else ''}, "
              f"outputs byte-identical: {farm_scale.describe(f)}; driver process {wall:.1f} s; load {f['load']:.1f}",
              flush=True)
        if opts.json_out:
            with open(opts.json_out, "w") as out:
                json.dump({"args": vars(opts), "figures": f, "samples": sampler.samples}, out, indent=1)
    finally:
        cluster.stop()
        shutil.rmtree(work, ignore_errors=True)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--kelvin", required=True)
    p.add_argument("--size", default="480x270")
    p.add_argument("--spp", type=int, default=32)
    p.add_argument("--tiles", type=int, default=16)
    p.add_argument("--nodes", default="1,2,3")
    p.add_argument("--rounds", type=int, default=2)
    p.add_argument("--json-out")
    p.add_argument("--scale", type=int, help="jobs of the farm-scale run (tasks: jobs x --tiles)")
    p.add_argument("--scale-size", default="64x64", help="image size of the farm-scale jobs")
    p.add_argument("--stub", action="store_true",
                   help="farm scale: tasks copy tiles rendered beforehand (the driver's and Ray's cost alone)")
    p.add_argument("--driver-args", default="", help="more options for kelvin_ray.py (--in-flight 8, say)")
    opts = p.parse_args()
    kelvin = os.path.abspath(opts.kelvin)
    if opts.scale:
        return scale(opts, kelvin)
    w, h = map(int, opts.size.split("x"))
    samples = w * h * opts.spp
    rows = []
    for nodes in map(int, opts.nodes.split(",")):
        work = tempfile.mkdtemp(prefix="kray-bench-", dir="/tmp")
        cluster = Cluster(os.path.join(os.path.dirname(sys.executable), "ray"), work, workers=nodes - 1)
        try:
            cluster.start()
            manifest = os.path.join(work, "jobs.json")
            with open(manifest, "w") as f:
                json.dump({"jobs": [{"name": "bench", "output": "tiled.exr", "size": opts.size, "spp": opts.spp}]}, f)
            single_out = os.path.join(work, "single.exr")
            for r in range(opts.rounds):
                single, single_cpu = single_render(opts, kelvin, single_out)
                s, whole = tiled_render(opts, kelvin, cluster, manifest, work)
                with open(single_out, "rb") as a, open(os.path.join(work, "tiled.exr"), "rb") as b:
                    check(a.read() == b.read(), "tiled image differs from the single render")
                tiles_cpu = sum(n["cpu_seconds"] for n in s["nodes"].values())
                row = {"nodes": nodes, "round": r + 1, "single_wall": single, "single_cpu": single_cpu,
                       "tiled_wall": s["wall_seconds"], "driver_wall": whole, "tiles_cpu": tiles_cpu,
                       "overhead_per_tile_ms": 1e3 * (tiles_cpu - single_cpu) / opts.tiles,
                       "msamples_per_s": samples / s["wall_seconds"] / 1e6,
                       "speedup": single / s["wall_seconds"], "nodes_used": len(s["nodes"]),
                       "load": os.getloadavg()[0]}
                rows.append(row)
                print(f"{nodes} node(s), round {r + 1}: kelvin render --threads 1 {single:.2f} s ({single_cpu:.2f} CPU s); "
                      f"{opts.tiles} tiles on {row['nodes_used']} node(s): {s['wall_seconds']:.2f} s "
                      f"(driver {whole:.2f} s), {tiles_cpu:.2f} CPU s, overhead {row['overhead_per_tile_ms']:+.1f} ms "
                      f"CPU per tile; {row['msamples_per_s']:.3f} M samples/s, {row['speedup']:.2f}x the single render; "
                      f"load {row['load']:.1f}", flush=True)
        finally:
            cluster.stop()
            shutil.rmtree(work, ignore_errors=True)
    if opts.json_out:
        with open(opts.json_out, "w") as f:
            json.dump({"args": vars(opts), "samples": samples, "rows": rows}, f, indent=1)


if __name__ == "__main__":
    main()
