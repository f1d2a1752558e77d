"""Rays alone: closest-hit and any-hit rays/s of kelvin and Mitsuba 3 on the same rays and the same glTF file.

Writes two ray sets for a scene (default tests/data/gltf/bench/sphere_65k.glb):
  coherent   - a 1024 x 1024 pinhole camera looking at the sphere from (0, 2, 6);
  incoherent - rays leaving the floor (y = 1e-3, x and z in [-3, 3]) in uniform random upper-hemisphere directions.
Each set is traced by Mitsuba (`ray_intersect_preliminary`, `ray_test`; best of --repeat after a warm-up) and by
kelvin's `examples/ray_throughput.rs` (one ray at a time in parallel batches, and 16-ray packets) from the same
f32 file. Both use every core. Prints a Markdown table.

  /tmp/mitsuba-venv/bin/python bench/mitsuba/rays.py   (the venv of bench/mitsuba/README.md: Mitsuba and numpy)
A kelvin built with `--features ray-stats` also reports the nodes, leaf blocks and triangles each single ray tested
(the counting costs time: take the rates from a build without it).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def make_rays(kind, n, seed=7):
    import numpy as np
    rng = np.random.default_rng(seed)
    if kind == "coherent":
        side = int(round(n ** 0.5))
        eye = np.array([0.0, 2.0, 6.0])
        fwd = np.array([0.0, 1.0, 0.0]) - eye
        fwd /= np.linalg.norm(fwd)
        right = np.cross(fwd, [0.0, 1.0, 0.0])
        right /= np.linalg.norm(right)
        up = np.cross(right, fwd)
        half = np.tan(np.radians(45.0) / 2)
        s = (np.arange(side) + 0.5) / side * 2 - 1
        x, y = np.meshgrid(s * half, -s * half)
        d = fwd + x[..., None] * right + y[..., None] * up
        d = d.reshape(-1, 3)
        o = np.broadcast_to(eye, d.shape)
    else:
        o = np.stack([rng.uniform(-3, 3, n), np.full(n, 1e-3), rng.uniform(-3, 3, n)], axis=1)
        d = rng.normal(size=(n, 3))
        d[:, 1] = np.abs(d[:, 1])
    d = d / np.linalg.norm(d, axis=1, keepdims=True)
    t = np.full((len(d), 1), 1e30)
    return np.concatenate([o, d, t], axis=1).astype("<f4")


def mitsuba_side(python, scene, files, repeat):
    """Runs this script's --mitsuba-child mode in the Mitsuba venv; returns {kind: (closest/s, any/s, hits, blocked)}."""
    cmd = [python, os.path.abspath(__file__), "--mitsuba-child", "--repeat", str(repeat), scene] + files
    env = dict(os.environ)
    llvm = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"
    if os.path.exists(llvm):
        env.setdefault("DRJIT_LIBLLVM_PATH", llvm)
    out = subprocess.run(cmd, check=True, capture_output=True, text=True, env=env).stdout
    return json.loads(out.strip().splitlines()[-1])


def mitsuba_child(scene_path, files, repeat):
    sys.path.insert(0, HERE)
    import numpy as np
    import mitsuba_gltf as mg
    mi = mg.setup_mitsuba("llvm_ad_rgb")
    import drjit as dr
    args, w, h = mg.parse_args([scene_path])
    warn = mg.Warnings()
    d, _ = mg.build_scene(mi, mg.GltfScene(scene_path, warn), args, w, h, warn)
    scene = mi.load_dict(d)
    res = {}
    for f in files:
        r = np.fromfile(f, dtype="<f4").reshape(-1, 7)
        ray = mi.Ray3f(o=mi.Point3f(*[mi.Float(r[:, i]) for i in range(3)]),
                       d=mi.Vector3f(*[mi.Float(r[:, i]) for i in range(3, 6)]))
        ray.maxt = mi.Float(r[:, 6])
        dr.eval(ray)

        def timed(fn):
            out = fn()
            dr.eval(out)
            dr.sync_thread()
            best = float("inf")
            for _ in range(repeat):
                t = time.perf_counter()
                out = fn()
                dr.eval(out)
                dr.sync_thread()
                best = min(best, time.perf_counter() - t)
            return best, out
        tc, pi = timed(lambda: scene.ray_intersect_preliminary(ray).is_valid())
        ta, blocked = timed(lambda: scene.ray_test(ray))
        n = len(r)
        res[f] = [n / tc, n / ta, int(dr.count(pi)[0]), int(dr.count(blocked)[0])]
    print(json.dumps(res))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--python", default=os.environ.get("MITSUBA_PYTHON", sys.executable),
                    help="python of the Mitsuba venv (default $MITSUBA_PYTHON or this python)")
    ap.add_argument("--scene", default=os.path.join(ROOT, "tests/data/gltf/bench/sphere_65k.glb"))
    ap.add_argument("--rays", type=int, default=1 << 20, help="rays per set (default 1M)")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--kelvin", default=os.path.join(ROOT, "target/dist/examples/ray_throughput"),
                    help="the built example (cargo build --profile dist --example ray_throughput)")
    ap.add_argument("--mitsuba-child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("files", nargs="*", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.mitsuba_child:
        return mitsuba_child(a.files[0], a.files[1:], a.repeat)
    if not os.path.isfile(a.kelvin):
        sys.exit(f"rays.py: {a.kelvin} is missing: cargo build --profile dist --example ray_throughput")
    tmp = tempfile.mkdtemp(prefix="kelvin-rays-")
    files = {}
    for kind in ("coherent", "incoherent"):
        files[kind] = os.path.join(tmp, f"{kind}.f32")
        make_rays(kind, a.rays).tofile(files[kind])
    rows = []
    for kind, f in files.items():
        k = json.loads(subprocess.run([a.kelvin, a.scene, f, str(a.repeat)], check=True, capture_output=True,
                                      text=True).stdout.strip().splitlines()[-1])
        m = mitsuba_side(a.python, a.scene, [f], a.repeat)[f]
        if (k["hits"], k["blocked"]) != (m[2], m[3]):
            print(f"note: {kind}: kelvin hits/blocked {k['hits']}/{k['blocked']}, Mitsuba {m[2]}/{m[3]}",
                  file=sys.stderr)
        rows.append((kind, k, m))
    # Mitsuba's closest-hit column evaluates a hit-or-miss mask only (Dr.Jit drops the unused
    # fields); kelvin's like-for-like column is `closest_hit_ref`, without a record.
    print(f"| rays ({a.rays:,} per set, {os.path.basename(a.scene)}) | kelvin one at a time | kelvin packets | "
          f"kelvin without records | Mitsuba | best kelvin / Mitsuba | without records / Mitsuba |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for kind, k, m in rows:
        for what, one, pk, bare, mm in (
                ("closest hit", k["closest_per_s"], k["closest_packet_per_s"], k["closest_ref_per_s"], m[0]),
                ("any hit", k["any_per_s"], k["any_packet_per_s"], None, m[1])):
            bare_cells = (f"{bare / 1e6:.1f} M/s", f"{bare / mm:.2f}") if bare else ("", "")
            print(f"| {kind} {what} | {one / 1e6:.1f} M/s | {pk / 1e6:.1f} M/s | {bare_cells[0]} | "
                  f"{mm / 1e6:.1f} M/s | {max(one, pk) / mm:.2f} | {bare_cells[1]} |")
    # Time per ray on one thread's share (rays/s over the threads), and with a `ray-stats` build what
    # each single ray tested: whether node tests, leaf tests or the rest bound it.
    threads = rows[0][1]["threads"]
    print(f"\n| rays, ns per ray per thread ({threads} threads) | kelvin single | kelvin packets | Mitsuba | "
          f"nodes / ray | leaf blocks / ray | triangles / ray |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for kind, k, m in rows:
        for what, one, pk, mm, walk in (
                ("closest hit", k["closest_ref_per_s"], k["closest_packet_per_s"], m[0], k.get("closest_walk")),
                ("any hit", k["any_per_s"], k["any_packet_per_s"], m[1], k.get("any_walk"))):
            counts = ([f"{walk[c]:.2f}" for c in ("nodes", "blocks", "triangles")] if walk
                      else ["(build with --features ray-stats)", "", ""])
            print(f"| {kind} {what} | {threads * 1e9 / one:.0f} | {threads * 1e9 / pk:.0f} | "
                  f"{threads * 1e9 / mm:.0f} | " + " | ".join(counts) + " |")


if __name__ == "__main__":
    main()
