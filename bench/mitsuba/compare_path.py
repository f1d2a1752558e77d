#!/usr/bin/env python3
"""kelvin's path tracer against Mitsuba 3's `path` integrator on Lambertian copies of real glTF files.

    /tmp/mitsuba-venv/bin/python bench/mitsuba/compare_path.py [--kelvin /tmp/kelvin-path] [--size 128x128]
        [--spp 64] [--ref-mult 16] [--depths 5,1] [--scenes cornell_box,env_objects] [--out-dir /tmp/peers]
        [--variant llvm_ad_rgb] [--brdf lambertian|gltf] [--speed] [--speed-spp 256] [--rounds 3] [--json-out FILE]

Per scene: scripts/make_lambertian_copy.py writes a copy whose materials are Lambertian and whose emitters are
one-sided (Mitsuba's `principled` is not glTF's BRDF and its area lights emit from the front only). Then, for
each kelvin depth d (`--max-depth d`: d surfaces after the camera's at most, 1 = direct lighting):
  kelvin  `render --integrator path --max-depth d` at N spp (seed 0)
  Mitsuba `path` with max_depth d+1 (Mitsuba counts the camera's segment too) at N spp (seed 1)
  Mitsuba reference: the same at N*M spp (seed 2)
and prints
  mean k/ref, mean m/ref  image mean ratio (all three channels) against the reference; goal: k/ref within 2%
  k/m                     kelvin's mean over Mitsuba@N's
  RMSE ratio              per-pixel RMSE(kelvin@N, ref) / RMSE(Mitsuba@N, ref); goal: within 1.5 (the
                          reference's own noise, 1/M of Mitsuba@N's variance, is in both)
  over kelvin's own noise RMSE(kelvin@N, ref) / (RMSE(kelvin@N, kelvin@N seed 1) / sqrt 2): ~1 when kelvin
                          is unbiased per pixel, whatever the other renderer's sampler
  worst tile              of an 8x8 grid of tiles, the one where kelvin's mean departs most from the
                          reference's, with Mitsuba@N's ratio there (noise level) and the tile's pixel box
With --brdf gltf, the copy keeps the file's materials (only the emitters become one-sided) and Mitsuba renders
them with gltf_bsdf.py, glTF's BRDF written from the specification, instead of `principled`.
With --speed: camera samples/s and rays/s of both, alternating kelvin and Mitsuba (--variant, the same max
depth, Mitsuba's rr_depth = kelvin's --roulette-depth) --rounds times, best of each. kelvin's own line
(`rendered ... in T s: A M samples/s, B M shadow rays/s, C M BSDF rays/s`) times the render without loading the
file; its first frame also builds the BVH, light and env tables, so a 1-spp render is timed as well and the
"net" rate is (N-1)*W*H / (T_N - T_1). Mitsuba: mitsuba_gltf.py's best of 3 renders after a warm-up, loading
excluded. Mitsuba does not count rays: its rays/s is estimated as its samples/s times kelvin's rays per sample
(camera + shadow + BSDF rays), which assumes the same path lengths.
Run it with the Mitsuba venv's python (numpy, mitsuba for the EXR reader); renders run one at a time.
"""
import argparse
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
sys.path.insert(0, str(HERE))
from compare_exr import load_exr  # noqa: E402

LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"
DATA = REPO / "tests" / "data"
# scene name -> (file, env map or None, env intensity); the same files and env as `kelvin bench render --list`
SCENES = {
    "cornell_box": ("gltf/bevy/CornellBox.glb", None, 1.0),
    "env_objects": ("gltf/bench/env_objects.glb", "env/spiaggia_di_mondello_1k.hdr", 1.0),
    "mixed_lighting": ("gltf/bevy/MixedLightingExample/MixedLightingExample.gltf", None, 1.0),
}
KELVIN_LINE = re.compile(r"rendered (\d+)x(\d+) at (\d+) spp in ([\d.]+) s: ([\d.]+) M samples/s, "
                         r"([\d.]+) M shadow rays/s, ([\d.]+) M BSDF rays/s")


def run(cmd, env=None):
    cmd = [str(c) for c in cmd]
    print("$ " + " ".join(cmd), file=sys.stderr, flush=True)
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    if p.returncode != 0:
        sys.stderr.write(p.stdout + p.stderr)
        raise SystemExit(f"failed (exit {p.returncode}): {cmd[0]}")
    return p.stdout


def kelvin_render(a, scene, env, depth, spp, seed, out, size=None):
    cmd = [a.kelvin, "render", scene, "--integrator", "path", "--max-depth", depth, "--roulette-depth",
           a.roulette_depth, "--spp", spp, "--size", size or a.size, "--seed", seed, "-o", out]
    if env:
        cmd += ["--env", env[0], "--env-intensity", env[1]]
    m = KELVIN_LINE.search(run(cmd))
    if not m:
        raise SystemExit("kelvin: no 'rendered ...' line in its output")
    w, h, n = (int(x) for x in m.group(1, 2, 3))
    t, sps, shadow, bsdf = (float(x) for x in m.group(4, 5, 6, 7))
    return {"seconds": t, "samples": w * h * n, "samples_per_s": sps * 1e6,
            "shadow_rays_per_s": shadow * 1e6, "bsdf_rays_per_s": bsdf * 1e6}


def mitsuba_render(a, scene, env, depth, spp, seed, out=None, repeat=1, size=None):
    cmd = [sys.executable, HERE / "mitsuba_gltf.py", scene, "--integrator", "path", "--max-depth", depth + 1,
           "--rr-depth", a.roulette_depth, "--spp", spp, "--size", size or a.size, "--seed", seed,
           "--variant", a.variant, "--repeat", repeat, "--json"]
    if out:
        cmd += ["--out", out]
    if env:
        cmd += ["--env", env[0], "--env-intensity", env[1]]
    if a.brdf == "gltf":
        cmd += ["--gltf-brdf"]
    out_text = run(cmd, a.env)
    return json.loads([ln for ln in out_text.splitlines() if ln.startswith("{")][-1])


def tiles(img, n=8):
    """-> (n, n) tile means (over RGB) and the tiles' pixel boxes."""
    h, w = img.shape[:2]
    ys, xs = np.linspace(0, h, n + 1).astype(int), np.linspace(0, w, n + 1).astype(int)
    means = np.array([[img[ys[i]:ys[i + 1], xs[j]:xs[j + 1]].mean() for j in range(n)] for i in range(n)])
    return means, ys, xs


def image_metrics(k, m, ref, k2=None):
    """k, m: the two renderers at N spp; ref: the reference; k2: kelvin at another seed (its own noise)."""
    rmse = lambda x, y=ref: float(np.sqrt(((x - y) ** 2).mean()))  # noqa: E731
    r = {"mean_k_ref": float(k.mean() / ref.mean()), "mean_m_ref": float(m.mean() / ref.mean()),
         "mean_k_m": float(k.mean() / m.mean()),
         "mean_k_ref_rgb": [float(x) for x in k.reshape(-1, 3).mean(0) / ref.reshape(-1, 3).mean(0)],
         "rmse_k": rmse(k), "rmse_m": rmse(m)}
    r["rmse_ratio"] = r["rmse_k"] / r["rmse_m"]
    if k2 is not None:  # RMSE(k, ref) over kelvin's own noise: ~1 (plus the reference's noise) if unbiased
        r["rmse_k_noise"] = rmse(k, k2) / np.sqrt(2.0)
        r["rmse_k_over_noise"] = r["rmse_k"] / r["rmse_k_noise"]
    tk, ys, xs = tiles(k)
    tm, _, _ = tiles(m)
    tr, _, _ = tiles(ref)
    lit = tr > 0.02 * tr.max()  # tiles with some light
    dev = np.where(lit, np.abs(tk / np.where(lit, tr, 1) - 1), -1)
    i, j = np.unravel_index(np.argmax(dev), dev.shape)
    r["worst_tile"] = {"k_ref": float(tk[i, j] / tr[i, j]), "m_ref": float(tm[i, j] / tr[i, j]),
                       "x": [int(xs[j]), int(xs[j + 1])], "y": [int(ys[i]), int(ys[i + 1])]}
    return r


def accuracy(a, name, scene, env, results):
    for d in a.depths:
        tag = f"{a.out_dir}/{name}_{a.brdf}_d{d}"
        kelvin_render(a, scene, env, d, a.spp, 0, f"{tag}_kelvin.exr")
        kelvin_render(a, scene, env, d, a.spp, 1, f"{tag}_kelvin_seed1.exr")
        mitsuba_render(a, scene, env, d, a.spp, 1, f"{tag}_mitsuba.exr")
        mitsuba_render(a, scene, env, d, a.spp * a.ref_mult, 2, f"{tag}_ref.exr")
        k, m, ref, k2 = (load_exr(f"{tag}_{s}.exr") for s in ("kelvin", "mitsuba", "ref", "kelvin_seed1"))
        r = image_metrics(k, m, ref, k2)
        r.update({"scene": name, "brdf": a.brdf, "depth": d, "mitsuba_max_depth": d + 1})
        results["accuracy"].append(r)
        wt = r["worst_tile"]
        ok = abs(r["mean_k_ref"] - 1) <= 0.02 and r["rmse_ratio"] <= 1.5
        print(f"{name} ({a.brdf}) d={d}: mean k/ref {r['mean_k_ref']:.4f} (RGB {'/'.join(f'{x:.3f}' for x in r['mean_k_ref_rgb'])}),"
              f" m/ref {r['mean_m_ref']:.4f}, k/m {r['mean_k_m']:.4f}; RMSE ratio {r['rmse_ratio']:.3f} (over kelvin's own noise {r['rmse_k_over_noise']:.3f}); worst tile "
              f"x{wt['x']} y{wt['y']}: k/ref {wt['k_ref']:.3f}, m/ref {wt['m_ref']:.3f}  {'ok' if ok else 'OUTSIDE GOALS'}",
              flush=True)


def speed(a, name, scene, env, results):
    d, n = a.speed_depth, a.speed_spp
    tmp = f"{a.out_dir}/{name}_speed.exr"
    k_runs, k1_runs, m_runs, load = [], [], [], [os.getloadavg()[0]]
    for _ in range(a.rounds):
        k1_runs.append(kelvin_render(a, scene, env, d, 1, 0, tmp))
        k_runs.append(kelvin_render(a, scene, env, d, n, 0, tmp))
        m_runs.append(mitsuba_render(a, scene, env, d, n, 0, repeat=3))
        load.append(os.getloadavg()[0])
    k = min(k_runs, key=lambda r: r["seconds"])
    t1 = min(r["seconds"] for r in k1_runs)
    m_sps = max(r["samples_per_s"] for r in m_runs)
    rays_per_sample = 1 + (k["shadow_rays_per_s"] + k["bsdf_rays_per_s"]) / k["samples_per_s"]
    net = (k["samples"] - k["samples"] / n) / max(k["seconds"] - t1, 1e-9)
    r = {"scene": name, "depth": d, "spp": n, "size": a.size, "kelvin_seconds": k["seconds"], "kelvin_1spp_seconds": t1,
         "kelvin_samples_per_s": k["samples_per_s"], "kelvin_net_samples_per_s": net,
         "kelvin_rays_per_sample": rays_per_sample, "kelvin_rays_per_s": k["samples_per_s"] * rays_per_sample,
         "mitsuba_seconds": min(r["seconds_best"] for r in m_runs), "mitsuba_samples_per_s": m_sps,
         "mitsuba_rays_per_s_est": m_sps * rays_per_sample, "ratio": k["samples_per_s"] / m_sps,
         "ratio_net": net / m_sps, "kelvin_runs": k_runs, "mitsuba_runs": [x["seconds_all"] for x in m_runs],
         "load_average_1min": load, "threads_mitsuba": m_runs[0]["threads"]}
    results["speed"].append(r)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kelvin", default=str(REPO / "target" / "dist" / "kelvin"))
    ap.add_argument("--size", default="128x128")
    ap.add_argument("--spp", type=int, default=64, help="spp of the compared renders (default 64)")
    ap.add_argument("--ref-mult", type=int, default=16, help="the reference has spp x this (default 16)")
    ap.add_argument("--depths", default="5,1", help="kelvin --max-depth values (default 5,1)")
    ap.add_argument("--roulette-depth", type=int, default=3, help="kelvin --roulette-depth = Mitsuba rr_depth")
    ap.add_argument("--scenes", default="cornell_box,env_objects", help=f"comma-separated, of {list(SCENES)}")
    ap.add_argument("--out-dir", default="/tmp/peers", help="Lambertian copies and EXRs go here")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--brdf", choices=["lambertian", "gltf"], default="lambertian",
                    help="lambertian: Lambertian copies; gltf: the file's materials, Mitsuba with gltf_bsdf.py")
    ap.add_argument("--no-accuracy", action="store_true", help="skip the image comparison")
    ap.add_argument("--speed", action="store_true", help="also time both renderers")
    ap.add_argument("--speed-spp", type=int, default=256)
    ap.add_argument("--speed-depth", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=3, help="alternating timing rounds; the best counts")
    ap.add_argument("--json-out", default=None)
    a = ap.parse_args(argv)
    a.depths = [int(x) for x in a.depths.split(",")]
    a.env = dict(os.environ)
    if "DRJIT_LIBLLVM_PATH" not in a.env and Path(LLVM).is_file():
        a.env["DRJIT_LIBLLVM_PATH"] = LLVM
    if not Path(a.kelvin).is_file():
        raise SystemExit(f"{a.kelvin}: not found (give --kelvin)")
    os.makedirs(a.out_dir, exist_ok=True)
    results = {"conditions": {k: v for k, v in vars(a).items() if k != "env"}, "accuracy": [], "speed": []}
    for name in a.scenes.split(","):
        if name not in SCENES:
            raise SystemExit(f"unknown scene {name}; known: {list(SCENES)}")
        rel, env_map, env_int = SCENES[name]
        src = DATA / rel
        copy = Path(a.out_dir) / name / (a.brdf + src.suffix)
        run([sys.executable, REPO / "scripts" / "make_lambertian_copy.py"]
            + (["--emitters-only"] if a.brdf == "gltf" else []) + [src, copy])
        env = (DATA / env_map, env_int) if env_map else None
        if not a.no_accuracy:
            accuracy(a, name, copy, env, results)
        if a.speed:
            speed(a, name, copy, env, results)
    if results["speed"]:
        print(f"\nspeed: {a.size}, kelvin --max-depth {a.speed_depth} vs Mitsuba {a.variant} path max_depth "
              f"{a.speed_depth + 1}, {a.speed_spp} spp, best of {a.rounds} alternating rounds\n")
        loads = [x for r in results["speed"] for x in r["load_average_1min"]]
        print(f"machine: {os.cpu_count()} cores, 1-min load average {min(loads):.1f}-{max(loads):.1f} during the runs "
              f"(other users' work included)\n")
        print("| scene | kelvin M samples/s (net of 1-spp frame) | kelvin M rays/s (rays/sample) "
              "| Mitsuba M samples/s | Mitsuba M rays/s (est.) | ratio (net) |")
        print("|---|---:|---:|---:|---:|---:|")
        for r in results["speed"]:
            print(f"| {r['scene']} | {r['kelvin_samples_per_s'] / 1e6:.2f} ({r['kelvin_net_samples_per_s'] / 1e6:.2f}) "
                  f"| {r['kelvin_rays_per_s'] / 1e6:.2f} ({r['kelvin_rays_per_sample']:.2f}) "
                  f"| {r['mitsuba_samples_per_s'] / 1e6:.2f} | {r['mitsuba_rays_per_s_est'] / 1e6:.2f} "
                  f"| {r['ratio']:.2f} ({r['ratio_net']:.2f}) |")
    if a.json_out:
        Path(a.json_out).write_text(json.dumps(results, indent=1) + "\n")


if __name__ == "__main__":
    main()
