#!/usr/bin/env python3
"""Splitting overhead and scaling: one job as N tiles on local Ray clusters of 1, 2 and 3 nodes (1 CPU each,
one kelvin thread per tile) against one `kelvin render --threads 1` of the same image, alternated `--rounds`
times; checks that the images are byte-identical.

    python bench_cluster.py --kelvin target/release/kelvin [--size 480x270] [--spp 32] [--tiles 16] [--nodes 1,2,3]
        [--rounds 2] [--json-out FILE]

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


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--kelvin", required=True)
    p.add_argument("--size", default="480x270")
    p.add_argument("--spp", type=int, default=32)
    p.add_argument("--tiles", type=int, default=16)
    p.add_argument("--nodes", default="1,2,3")
    p.add_argument("--rounds", type=int, default=2)
    p.add_argument("--json-out")
    opts = p.parse_args()
    kelvin = os.path.abspath(opts.kelvin)
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
