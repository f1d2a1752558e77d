#!/usr/bin/env python3
"""kelvin against Mitsuba 3 on the render suite: camera samples per second on the same files.

    python3 bench/mitsuba/compare.py --python /tmp/mitsuba-venv/bin/python [--size 128x128] [--spp N]
        [--scenes a,b] [--rounds 1] [--repeat 3] [--kelvin target/dist/kelvin] [--json-out FILE]
        [--integrator direct|path] [--max-depth 5]

For each scene of `kelvin bench render --list`, one renderer at a time: kelvin's
`bench render --scenes NAME --size S --json` (which names the file, the environment map and the spp it used),
then Mitsuba's mitsuba_gltf.py (beside this script) on the same file, size and spp, with `--integrator direct`
and the same --env/--env-intensity. With `--integrator path --max-depth D`, kelvin's path tracer at depth D (D
surfaces after the camera's, roulette from kelvin's default depth 3) against Mitsuba's `path` with max_depth D + 1
(Mitsuba counts the camera's segment) and rr_depth 3; M samples/s are camera samples (paths) per second. With --rounds R > 1 the pair is repeated R times (alternating) and each
renderer's best round counts. Both time the best of --repeat renders after a warm-up, loading excluded.
Prints a Markdown table (scene | spp | kelvin M samples/s | Mitsuba M samples/s | ratio kelvin/Mitsuba) and the
geometric mean of the ratios. Progress and both renderers' logs go to stderr.

The Mitsuba Python (a venv with mitsuba==3.9.1 drjit==1.5.0 numpy pygltflib, see README.md) comes from --python or
the MITSUBA_PYTHON environment variable. Python 3 standard library only; build kelvin first
(`cargo build --profile dist`).
"""

import argparse
import json
import math
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"


def last_json(stdout, what):
    for line in reversed(stdout.strip().splitlines()):
        line = line.strip()
        if line.startswith("{"):
            return json.loads(line)
    raise SystemExit(f"{what}: no JSON line in its output")


def run(cmd, what, env=None):
    print("$ " + " ".join(str(c) for c in cmd), file=sys.stderr, flush=True)
    p = subprocess.run([str(c) for c in cmd], stdout=subprocess.PIPE, stderr=None, text=True, env=env)
    if p.returncode != 0:
        raise SystemExit(f"{what} failed (exit {p.returncode})")
    sys.stderr.write(p.stdout)
    return last_json(p.stdout, what)


def suite_names(kelvin):
    out = subprocess.run([str(kelvin), "bench", "render", "--list"], stdout=subprocess.PIPE, text=True, check=True)
    return [line.split(":", 1)[0] for line in out.stdout.splitlines() if ":" in line]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--python", default=os.environ.get("MITSUBA_PYTHON"), help="Python of the Mitsuba venv")
    ap.add_argument("--kelvin", default=str(REPO / "target" / "dist" / "kelvin"), help="the kelvin binary")
    ap.add_argument("--size", default="128x128")
    ap.add_argument("--spp", type=int, default=None, help="spp for every scene (default: each scene's own)")
    ap.add_argument("--scenes", default=None, help="comma-separated suite scenes (default: all)")
    ap.add_argument("--rounds", type=int, default=1, help="alternating kelvin/Mitsuba rounds; the best counts")
    ap.add_argument("--repeat", type=int, default=3, help="timed renders per run, for both (default 3)")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--json-out", default=None, help="write every run's JSON here")
    ap.add_argument("--integrator", choices=["direct", "path"], default="direct")
    ap.add_argument("--max-depth", type=int, default=5, help="kelvin's path depth with --integrator path (default 5)")
    args = ap.parse_args(argv)
    if not args.python:
        raise SystemExit("give the Mitsuba venv's python with --python or MITSUBA_PYTHON (see README.md)")
    kelvin = Path(args.kelvin)
    if not kelvin.is_file():
        raise SystemExit(f"{kelvin}: not found; run `cargo build --profile dist` first")
    env = dict(os.environ)
    if "DRJIT_LIBLLVM_PATH" not in env and Path(LLVM).is_file():
        env["DRJIT_LIBLLVM_PATH"] = LLVM

    names = suite_names(kelvin)
    if args.scenes:
        wanted = [s.strip() for s in args.scenes.split(",") if s.strip()]
        unknown = [s for s in wanted if s not in names]
        if unknown:
            raise SystemExit(f"unknown scenes {unknown}; the suite has {names}")
        names = [n for n in names if n in wanted]

    results = []
    for name in names:
        k_runs, m_runs = [], []
        for _ in range(max(1, args.rounds)):
            cmd = [kelvin, "bench", "render", "--scenes", name, "--size", args.size, "--repeat", args.repeat, "--json",
                   "--integrator", args.integrator, "--max-depth", args.max_depth]
            if args.spp:
                cmd += ["--spp", args.spp]
            row = run(cmd, f"kelvin on {name}")["rows"][0]
            k_runs.append(row)
            cmd = [args.python, HERE / "mitsuba_gltf.py", row["file"], "--size", args.size, "--spp", row["spp"],
                   "--variant", args.variant, "--integrator", args.integrator, "--repeat", args.repeat, "--json"]
            if args.integrator == "path":
                cmd += ["--max-depth", args.max_depth + 1, "--rr-depth", 3]
            if row.get("env"):
                cmd += ["--env", row["env"], "--env-intensity", row["env_intensity"]]
            m_runs.append(run(cmd, f"Mitsuba on {name}", env))
        k = max(r["samples_per_s"] for r in k_runs)
        m = max(r["samples_per_s"] for r in m_runs)
        results.append({"scene": name, "spp": k_runs[0]["spp"], "kelvin": k, "mitsuba": m, "ratio": k / m,
                        "kelvin_runs": k_runs, "mitsuba_runs": m_runs})

    how = "direct" if args.integrator == "direct" else f"path max_depth {args.max_depth + 1} (kelvin depth {args.max_depth})"
    print(f"\n{args.size}, {args.variant} {how} for Mitsuba, best of {args.repeat} renders"
          f" x {max(1, args.rounds)} round(s)\n")
    print("| scene | spp | kelvin M samples/s | Mitsuba M samples/s | ratio |")
    print("|---|---:|---:|---:|---:|")
    for r in results:
        print(f"| {r['scene']} | {r['spp']} | {r['kelvin'] / 1e6:.2f} | {r['mitsuba'] / 1e6:.2f} | {r['ratio']:.2f} |")
    if results:
        gmean = math.exp(sum(math.log(r["ratio"]) for r in results) / len(results))
        print(f"| geometric mean | | | | {gmean:.2f} |")
    if args.json_out:
        Path(args.json_out).write_text(json.dumps(results, indent=1) + "\n")


if __name__ == "__main__":
    main()
