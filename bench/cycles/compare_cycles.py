#!/usr/bin/env python3
"""kelvin's path tracer against Blender Cycles on the same glTF file (original materials by default).

    /tmp/mitsuba-venv/bin/python bench/cycles/compare_cycles.py --cycles-python /tmp/cycles-venv/bin/python
        [--kelvin /tmp/kelvin-path] [--scene tests/data/gltf/bevy/CornellBox.glb] [--size 128x128] [--spp 64]
        [--ref-mult 16] [--depths 5,1] [--lambertian] [--filter-width 1.0] [--out-dir /tmp/peers/cycles]
        [--json-out FILE]

For each kelvin depth d: kelvin `render --integrator path --max-depth d` at N spp (seed 0), Cycles
(cycles_gltf.py beside this file, bounces d-1) at N spp (seed 1) and a Cycles reference at N*M spp (seed 2).
Prints the same figures as bench/mitsuba/compare_path.py: image mean ratio kelvin/reference (goal: within 2%),
Cycles@N/reference, per-pixel RMSE(kelvin@N, ref) / RMSE(Cycles@N, ref) (goal: within 1.5; Cycles samples
with a tabulated Sobol sequence, kelvin with independent random numbers, so this also measures the samplers),
RMSE(kelvin@N, ref) over kelvin's own noise (from a second kelvin seed; ~1 when unbiased), and the 8x8 tile
where kelvin departs most from the reference. With --lambertian both render the Lambertian, one-sided-emitter
copy of scripts/make_lambertian_copy.py instead (a check of units, camera and sidedness without the BRDFs).
Run it with the Mitsuba venv's python (numpy and its EXR reader); Cycles runs in its own venv's python.
"""
import argparse
import json
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
sys.path.insert(0, str(REPO / "bench" / "mitsuba"))
from compare_exr import load_exr  # noqa: E402
from compare_path import image_metrics, kelvin_render, run  # noqa: E402


def cycles_render(a, scene, depth, spp, seed, out):
    cmd = [a.cycles_python, HERE / "cycles_gltf.py", scene, "--size", a.size, "--spp", spp, "--max-depth", depth,
           "--seed", seed, "--out", out, "--filter-width", a.filter_width, "--json"]
    text = run(cmd)
    return json.loads([ln for ln in text.splitlines() if ln.startswith("{")][-1])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cycles-python", default="/tmp/cycles-venv/bin/python")
    ap.add_argument("--kelvin", default=str(REPO / "target" / "dist" / "kelvin"))
    ap.add_argument("--scene", default=str(REPO / "tests" / "data" / "gltf" / "bevy" / "CornellBox.glb"))
    ap.add_argument("--size", default="128x128")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--ref-mult", type=int, default=16)
    ap.add_argument("--depths", default="5,1")
    ap.add_argument("--roulette-depth", type=int, default=3, help="kelvin --roulette-depth")
    ap.add_argument("--lambertian", action="store_true", help="compare on the Lambertian copy")
    ap.add_argument("--filter-width", type=float, default=1.0, help="Cycles pixel filter width")
    ap.add_argument("--out-dir", default="/tmp/peers/cycles")
    ap.add_argument("--json-out", default=None)
    a = ap.parse_args(argv)
    out = Path(a.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    scene = Path(a.scene)
    label = scene.stem + ("_lambertian" if a.lambertian else "")
    if a.lambertian:
        copy = out / ("lambertian_" + scene.name)
        run([sys.executable, REPO / "scripts" / "make_lambertian_copy.py", scene, copy])
        scene = copy
    results = {"conditions": vars(a), "rows": []}
    for d in (int(x) for x in a.depths.split(",")):
        tag = out / f"{label}_d{d}"
        k = kelvin_render(a, scene, None, d, a.spp, 0, f"{tag}_kelvin.exr")
        kelvin_render(a, scene, None, d, a.spp, 1, f"{tag}_kelvin_seed1.exr")
        c = cycles_render(a, scene, d, a.spp, 1, f"{tag}_cycles.exr")
        cr = cycles_render(a, scene, d, a.spp * a.ref_mult, 2, f"{tag}_ref.exr")
        r = image_metrics(*(load_exr(f"{tag}_{s}.exr") for s in ("kelvin", "cycles", "ref", "kelvin_seed1")))
        r.update({"scene": label, "depth": d, "cycles_bounces": d - 1, "kelvin_seconds": k["seconds"],
                  "cycles_seconds": c["seconds"], "cycles_ref_seconds": cr["seconds"]})
        results["rows"].append(r)
        wt = r["worst_tile"]
        ok = abs(r["mean_k_ref"] - 1) <= 0.02 and r["rmse_ratio"] <= 1.5
        print(f"{label} d={d} (Cycles bounces {d - 1}): mean k/ref {r['mean_k_ref']:.4f} "
              f"(RGB {'/'.join(f'{x:.3f}' for x in r['mean_k_ref_rgb'])}), cycles/ref {r['mean_m_ref']:.4f}, "
              f"k/cycles {r['mean_k_m']:.4f}; RMSE ratio {r['rmse_ratio']:.3f} (over kelvin's own noise {r['rmse_k_over_noise']:.3f}); worst tile x{wt['x']} y{wt['y']}: "
              f"k/ref {wt['k_ref']:.3f}, cycles/ref {wt['m_ref']:.3f}  {'ok' if ok else 'OUTSIDE GOALS'}", flush=True)
    if a.json_out:
        Path(a.json_out).write_text(json.dumps(results, indent=1, default=str) + "\n")


if __name__ == "__main__":
    main()
