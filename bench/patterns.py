#!/usr/bin/env python3
"""The Sobol pattern against independent random numbers on the render suite (`kelvin bench render --list`):
per scene, the noise and the time of `kelvin render` at equal spp under `--pattern sobol` and `--pattern
independent`, and the efficiency (time to equal noise) that follows.

    /tmp/mitsuba-venv/bin/python bench/patterns.py [--kelvin target/dist/kelvin] [--size 128x128] [--spp 16]
        [--integrator path] [--seeds 8] [--scenes a,b] [--out-dir /tmp/peers/patterns] [--json-out FILE]

Per scene and pattern: --seeds K renders at N spp (seeds 0..K, K even). Noise = the mean over the pairs of seeds
(0, 1), (2, 3), ... of sum((a - b)^2) / 2 / sum(r^2) over the finite pixels, with r the mean of every render
(relative MSE of one render, measured between two seeds, so no reference is needed and none of its noise
enters; paths through glossy surfaces make rare bright samples, so a pair alone varies by 2-4x on CornellBox:
take 8 seeds or more there). The median over the pairs is shown too, which the rare bright samples move less. Time = the best of the
renders' own "rendered ... in T s" (the scene load
excluded). Efficiency = (noise_ind t_ind) / (noise_sobol t_sobol): how much sooner Sobol
reaches equal noise. Also the mean ratio sobol / independent (both unbiased: 1 within noise). EXRs are read
with Mitsuba's Bitmap (bench/mitsuba/compare_exr.py), hence the Mitsuba venv's python.
"""
import argparse
import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path.insert(0, str(HERE / "mitsuba"))
from compare_exr import load_exr  # noqa: E402

LIST_LINE = re.compile(r"^(\w+): (\S+)((?: --\S+ \S+)*), (\d+) spp at")
RENDERED = re.compile(r"rendered \d+x\d+ at \d+ spp in ([\d.]+) s")


def suite(kelvin):
    """(name, scene path, extra args) of every suite scene."""
    out = subprocess.run([kelvin, "bench", "render", "--list"], capture_output=True, text=True, check=True).stdout
    scenes = []
    for line in out.splitlines():
        m = LIST_LINE.match(line)
        if not m:
            continue
        extra = m.group(3).split()
        for i in range(0, len(extra), 2):
            if extra[i] == "--env":
                extra[i + 1] = str(REPO / "tests" / "data" / extra[i + 1])
        scenes.append((m.group(1), REPO / "tests" / "data" / m.group(2), extra))
    return scenes


def render(a, scene, extra, pattern, seed, out):
    cmd = [a.kelvin, "render", str(scene), *extra, "--size", a.size, "--spp", str(a.spp), "--integrator",
           a.integrator, "--pattern", pattern, "--seed", str(seed), "-o", str(out)]
    run = subprocess.run(cmd, capture_output=True, text=True)
    if run.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)}: {run.stderr}")
    return float(RENDERED.search(run.stderr + run.stdout).group(1)), load_exr(str(out))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kelvin", default=str(REPO / "target" / "dist" / "kelvin"))
    ap.add_argument("--size", default="128x128")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--integrator", default="path")
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--scenes", default="")
    ap.add_argument("--out-dir", default="/tmp/peers/patterns")
    ap.add_argument("--json-out")
    a = ap.parse_args()
    out = Path(a.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    wanted = set(filter(None, a.scenes.split(",")))
    rows = []
    seeds = range(a.seeds - a.seeds % 2 or 2)
    print(f"{a.integrator}, {a.size}, {a.spp} spp, {len(seeds)} seeds per pattern")
    print("| scene | noise Sobol | noise independent | noise ind / Sobol | median pair ind / Sobol | time Sobol s | "
          "time ind s | time Sobol / ind | efficiency | mean Sobol / ind |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name, scene, extra in suite(a.kelvin):
        if wanted and name not in wanted:
            continue
        r = {}
        # Alternating patterns, so that a change of load hits both.
        for seed in seeds:
            for pattern in ("sobol", "independent"):
                r[pattern, seed] = render(a, scene, extra, pattern, seed, out / f"{name}_{pattern}_{seed}.exr")
        images = [img for _, img in r.values()]
        ok = np.all([np.isfinite(i).all(-1) for i in images], axis=0)
        mean = np.mean(images, axis=0)[ok]
        norm = float((mean ** 2).sum())
        row = {"scene": name}
        for pattern in ("sobol", "independent"):
            runs = [r[pattern, s] for s in seeds]
            pairs = [float(((runs[k][1][ok] - runs[k + 1][1][ok]) ** 2).sum()) / 2 / norm for k in range(0, len(runs), 2)]
            row[pattern] = {"noise": float(np.mean(pairs)), "median": float(np.median(pairs)),
                            "seconds": min(t for t, _ in runs),
                            "sum": float(sum(img[ok].sum() for _, img in runs))}
        s, i = row["sobol"], row["independent"]
        row["noise_ratio"] = i["noise"] / s["noise"]
        row["median_ratio"] = i["median"] / s["median"]
        row["time_ratio"] = s["seconds"] / i["seconds"]
        row["efficiency"] = row["noise_ratio"] / row["time_ratio"]
        row["mean_ratio"] = s["sum"] / i["sum"]
        rows.append(row)
        print(f"| {name} | {s['noise']:.3e} | {i['noise']:.3e} | {row['noise_ratio']:.2f} | {row['median_ratio']:.2f} | "
              f"{s['seconds']:.3f} | "
              f"{i['seconds']:.3f} | {row['time_ratio']:.3f} | {row['efficiency']:.2f} | {row['mean_ratio']:.4f} |",
              flush=True)
    geo = lambda k: float(np.exp(np.mean([np.log(r[k]) for r in rows])))
    print(f"geometric means: noise ind / Sobol {geo('noise_ratio'):.2f} (median pair {geo('median_ratio'):.2f}), "
          f"time Sobol / ind {geo('time_ratio'):.3f}, "
          f"efficiency {geo('efficiency'):.2f}")
    if a.json_out:
        Path(a.json_out).write_text(json.dumps({"args": vars(a), "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
