#!/usr/bin/env python3
"""Splitting overhead: one job as N tiles on a local two-node Ray cluster (1 CPU each) against one
`kelvin render` of the same image using both CPUs, alternated `--rounds` times; checks the images match.

    python bench_cluster.py --kelvin target/release/kelvin --size 512x512 --spp 80 --tiles 16
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

from test_cluster import HERE, Cluster, check


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--kelvin", required=True)
    p.add_argument("--size", default="512x512")
    p.add_argument("--spp", type=int, default=80)
    p.add_argument("--tiles", type=int, default=16)
    p.add_argument("--rounds", type=int, default=2)
    opts = p.parse_args()
    kelvin = os.path.abspath(opts.kelvin)
    work = tempfile.mkdtemp(prefix="kray-bench-", dir="/tmp")
    cluster = Cluster(os.path.join(os.path.dirname(sys.executable), "ray"), work)
    try:
        cluster.start()
        manifest = os.path.join(work, "jobs.json")
        with open(manifest, "w") as f:
            json.dump({"jobs": [{"name": "bench", "output": "tiled.exr", "size": opts.size, "spp": opts.spp}]}, f)
        single_out = os.path.join(work, "single.exr")
        for r in range(opts.rounds):
            t, cpu = time.monotonic(), resource.getrusage(resource.RUSAGE_CHILDREN)
            run = subprocess.run([kelvin, "render", "-o", single_out, "--size", opts.size, "--spp", str(opts.spp)],
                                 capture_output=True, text=True, timeout=1200)
            single = time.monotonic() - t
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            single_cpu = after.ru_utime + after.ru_stime - cpu.ru_utime - cpu.ru_stime
            check(run.returncode == 0, run.stderr)
            summary = os.path.join(work, "summary.json")
            cmd = [sys.executable, os.path.join(HERE, "kelvin_ray.py"), manifest, "--kelvin", kelvin, "--force",
                   "--tiles", str(opts.tiles), "--address", cluster.address, "--summary", summary]
            t = time.monotonic()
            run = subprocess.run(cmd, env=cluster.env, capture_output=True, text=True, timeout=1200)
            whole = time.monotonic() - t
            check(run.returncode == 0, run.stdout + run.stderr)
            with open(summary) as f:
                s = json.load(f)
            with open(single_out, "rb") as a, open(os.path.join(work, "tiled.exr"), "rb") as b:
                check(a.read() == b.read(), "tiled image differs from the single render")
            tasks = sum(n["cpu_seconds"] for n in s["nodes"].values())
            print(f"round {r + 1}: kelvin render {single:.2f} s; {opts.tiles} tiles: driver {whole:.2f} s "
                  f"(tiles and merge {s['wall_seconds']:.2f} s), overhead {100 * (s['wall_seconds'] / single - 1):+.1f}% "
                  f"({100 * (whole / single - 1):+.1f}% with the driver's start); CPU seconds: render {single_cpu:.2f}, "
                  f"tiles {tasks:.2f} ({100 * (tasks / single_cpu - 1):+.1f}%)")
            for node, n in sorted(s["nodes"].items()):
                print(f"  node {node[:12]}: {n['tiles']} tiles, {n['task_seconds']:.2f} s in tasks "
                      f"({n['cpu_seconds']:.2f} CPU s), "
                      f"{n['tiles'] / s['wall_seconds']:.3f} tiles/s")
    finally:
        cluster.stop()
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
