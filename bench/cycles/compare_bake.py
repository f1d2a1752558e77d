#!/usr/bin/env python3
"""`kelvin bake lightmaps` against Cycles' DIFFUSE bake (bake_cycles.py) per mesh: mean ratio, RMSE against a
converged Cycles bake over each one's own noise, relMSE, and time to equal noise.

    /tmp/cycles-venv/bin/python bench/cycles/compare_bake.py [--kelvin /tmp/kbin/kelvin-main]
        [--scene tests/data/gltf/bevy/CornellBox.glb] [--size 256] [--spp 32] [--ref-mult 16] [--depths 16,1]
        [--albedo-floor 1e-4] [--two-sided-emitters] [--speed-rounds 0] [--out-dir /tmp/peers/cycles_bake]
        [--json-out FILE] [--reuse]

Scene: the Lambertian copy of scripts/make_lambertian_copy.py (one-sided emitters; bake_cycles.py makes Cycles'
emission of doubleSided-false materials front-only too), then every base-colour channel that is 0 raised to
--albedo-floor in the file both bake: Cycles' no-colour bake divides the diffuse light by the diffuse colour and,
where a channel of that is 0, fills it from the other channels (safe_divide_even_color: a red wall's G and B
become its R), where kelvin's texel is the irradiance a white surface gets in every channel. 1e-4 changes the
light the wall reflects in that channel by 1e-4 of the light reaching it.
--two-sided-emitters keeps the file's doubleSided true on emitters and Cycles' two-sided emission (a check of
kelvin's leak test on a two-sided lamp).
Runs, per kelvin depth d (Cycles bounces d - 1): kelvin at N spp seeds 0 and 1 and at N*M spp seed 2; Cycles
at N spp seeds 1 and 3 and the reference at N*M spp seed 2 (Cycles, so that the reference shares no code with
kelvin: kelvin's own bias shows against it). All on the CPU with all cores, one after another.
Texels compared ("clean"), per mesh, from the glTF alone (no output of either baker): texels whose 8x8 sub-points
all lie in triangles of one uv chart (so dilated margins, partly covered texels and texels across a seam are
out: the two bakers fill and sample those differently), and whose centre's 64 cosine-distributed directions
meet no back face first (kelvin drops such samples as leaks -- a floor under a box, a ceiling above a one-sided
lamp -- where Cycles averages the dark they see: the leak zone is reported apart, "zone").
Figures per mesh over its clean texels (RGB, float64):
  mean k/c     sum(kelvin@N) / sum(Cycles@N); mean k/c ref: kelvin@NM / Cycles@NM (less noise)
  RMSE k/c     RMSE(kelvin@N, ref) / RMSE(Cycles@N, ref)  (issue 41: within Cycles' own noise at equal samples)
  noise        RMSE(x@N seed a, x@N seed b) / sqrt(2): each baker's own per-texel noise at N spp
  k/noise      RMSE(kelvin@N, ref) / kelvin's noise (~1 when unbiased, plus the reference's noise)
  relMSE       sum((x - ref)^2) / sum(ref^2)
  speed        time to equal noise, Cycles over kelvin: (t_c relMSE_c) / (t_k relMSE_k) (relMSE ~ 1/spp), with
               the bakers' whole times (one run bakes every mesh: kelvin's "baked ... in T s", Cycles' bake call),
               per mesh and pooled over all meshes; 2-seed: noise^2 instead of relMSE; CPU: CPU seconds (all
               threads) instead of wall time, steadier on a shared machine. --speed-rounds R: R more alternating
               runs of each at N spp, the best times of R + 1 taken.
"""
import argparse
import json
import math
import os
import re
import resource
import struct
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(REPO / "scripts"))
from make_lambertian_copy import lambertian, read_gltf, write_glb  # noqa: E402

KELVIN_LINE = re.compile(r"baked \d+ lightmaps \(.*?\) at \d+ spp in (?P<seconds>[\d.]+) s")


def run(cmd):
    """-> (stdout, wall seconds, CPU seconds of the child (user + sys))."""
    cmd = [str(c) for c in cmd]
    print("$ " + " ".join(cmd), file=sys.stderr, flush=True)
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        sys.stderr.write(p.stdout + p.stderr)
        raise SystemExit(f"failed (exit {p.returncode}): {cmd[0]}")
    return p.stdout, wall, (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)


def load1():
    return os.getloadavg()[0]


def kelvin_bake(a, scene, depth, spp, seed, out):
    done = out / "run.json"
    if a.reuse and done.exists():
        return json.loads(done.read_text())
    load = load1()
    text, wall, cpu = run([a.kelvin, "bake", "lightmaps", scene, "-o", out, "--size", a.size, "--spp", spp,
                           "--max-depth", depth, "--seed", seed])
    m = KELVIN_LINE.search(text)
    if not m:
        raise SystemExit("kelvin: no 'baked ...' line in its output")
    index = json.loads((out / "lightmaps.json").read_text())
    r = {"seconds": float(m.group("seconds")), "wall": wall, "cpu": cpu, "load_before": load, "spp": spp, "seed": seed,
         "files": {v["mesh"]: v["exr"] for v in index["lightmaps"].values()}}
    done.write_text(json.dumps(r))
    return r


def cycles_bake(a, scene, depth, spp, seed, out):
    done = out / "run.json"
    if a.reuse and done.exists():
        return json.loads(done.read_text())
    load = load1()
    text, wall, cpu = run([a.cycles_python, HERE / "bake_cycles.py", scene, "-o", out, "--size", a.size, "--spp",
                           spp, "--max-depth", depth, "--seed", seed, "--margin", 4, "--json", "--emission-sides",
                           "two" if a.two_sided_emitters else "gltf"])
    j = json.loads([ln for ln in text.splitlines() if ln.startswith("{")][-1])
    r = {"seconds": j["bake_seconds"], "bake_cpu": j.get("bake_cpu_seconds"), "total_seconds": j["total_seconds"],
         "wall": wall, "cpu": cpu,
         "load_before": load, "spp": spp, "seed": seed, "notes": j["notes"],
         "files": {v["mesh"]: v["exr"] for v in j["lightmaps"].values()}}
    done.write_text(json.dumps(r))
    return r


# ---- the scene's geometry, from the glTF file ----

def gltf_meshes(path):
    """-> list of dicts per placed mesh: name, world triangles (T, 3, 3), uv1 (T, 3, 2) or None, chart (T,)."""
    doc, binary, glb = read_gltf(path)
    if not glb:
        raise SystemExit("compare_bake.py reads .glb files")

    def accessor(i):
        acc = doc["accessors"][i]
        bv = doc["bufferViews"][acc["bufferView"]]
        comps = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[acc["type"]]
        dtype = {5126: np.float32, 5125: np.uint32, 5123: np.uint16, 5121: np.uint8}[acc["componentType"]]
        off = bv.get("byteOffset", 0) + acc.get("byteOffset", 0)
        stride = bv.get("byteStride", 0) or comps * np.dtype(dtype).itemsize
        raw = np.frombuffer(binary, np.uint8, count=stride * (acc["count"] - 1) + comps * np.dtype(dtype).itemsize,
                            offset=off)
        rows = np.lib.stride_tricks.as_strided(raw, (acc["count"], comps * np.dtype(dtype).itemsize), (stride, 1))
        return np.ascontiguousarray(rows).view(dtype).reshape(acc["count"], comps)

    def local(node):
        if "matrix" in node:
            return np.array(node["matrix"], np.float64).reshape(4, 4).T
        t = np.eye(4)
        t[:3, 3] = node.get("translation", [0, 0, 0])
        x, y, z, w = node.get("rotation", [0, 0, 0, 1])
        r = np.eye(4)
        r[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
        s = np.diag(list(node.get("scale", [1, 1, 1])) + [1])
        return t @ r @ s

    placed = []

    def visit(i, parent):
        node = doc["nodes"][i]
        m = parent @ local(node)
        if "mesh" in node:
            mesh = doc["meshes"][node["mesh"]]
            tris, uvs, charts, n_chart = [], [], [], 0
            for prim in mesh["primitives"]:
                pos = accessor(prim["attributes"]["POSITION"]).astype(np.float64)
                pos = pos @ m[:3, :3].T + m[:3, 3]
                idx = accessor(prim["indices"]).ravel().astype(np.int64) if "indices" in prim else \
                    np.arange(len(pos))
                idx = idx.reshape(-1, 3)
                if np.linalg.det(m[:3, :3]) < 0:
                    idx = idx[:, ::-1]
                tris.append(pos[idx])
                uv = prim["attributes"].get("TEXCOORD_1")
                uvs.append(accessor(uv).astype(np.float64)[idx] if uv is not None else None)
                # Charts: triangles connected through shared vertex indices (union-find).
                parent_of = list(range(len(pos)))

                def find(k):
                    while parent_of[k] != k:
                        parent_of[k] = parent_of[parent_of[k]]
                        k = parent_of[k]
                    return k
                for t in idx:
                    for k in t[1:]:
                        parent_of[find(k)] = find(t[0])
                roots = [find(t[0]) for t in idx]
                ids = {r: n_chart + j for j, r in enumerate(sorted(set(roots)))}
                charts.append(np.array([ids[r] for r in roots]))
                n_chart += len(ids)
            has_uv = all(u is not None for u in uvs)
            placed.append({"name": mesh.get("name"), "tris": np.concatenate(tris),
                           "uv1": np.concatenate(uvs) if has_uv else None, "chart": np.concatenate(charts)})
        for c in node.get("children", []):
            visit(c, m)

    for i in doc["scenes"][doc.get("scene", 0)]["nodes"]:
        visit(i, np.eye(4))
    return placed


def interior_texels(mesh, size, sub=8):
    """-> (interior mask (size, size), centre points (size, size, 3), geometric normals (size, size, 3)).
    Interior: all sub x sub points of the texel in triangles of one chart. Row r = v in [r, r + 1] / size."""
    n = size * sub
    owner = np.full((n, n), -1, np.int64)  # chart, -2 where charts overlap
    tri_of = np.full((n, n), -1, np.int64)
    for t, (uv, chart) in enumerate(zip(mesh["uv1"], mesh["chart"])):
        p = uv * n - 0.5  # sub-point (i, j) sits at (j + 0.5, i + 0.5) / n
        lo = np.maximum(np.floor(p.min(0)).astype(int), 0)
        hi = np.minimum(np.ceil(p.max(0)).astype(int) + 1, n)
        if (hi <= lo).any():
            continue
        xs, ys = np.meshgrid(np.arange(lo[0], hi[0]), np.arange(lo[1], hi[1]))
        d1, d2 = p[1] - p[0], p[2] - p[0]
        det = d1[0] * d2[1] - d1[1] * d2[0]
        if abs(det) < 1e-12:
            continue
        qx, qy = xs - p[0][0], ys - p[0][1]
        b1 = (qx * d2[1] - qy * d2[0]) / det
        b2 = (d1[0] * qy - d1[1] * qx) / det
        inside = (b1 >= 0) & (b2 >= 0) & (b1 + b2 <= 1)
        yy, xx = ys[inside], xs[inside]
        cur = owner[yy, xx]
        owner[yy, xx] = np.where((cur == -1) | (cur == chart), chart, -2)
        tri_of[yy, xx] = t
    blocks = owner.reshape(size, sub, size, sub).transpose(0, 2, 1, 3).reshape(size, size, sub * sub)
    interior = (blocks[..., :1] >= 0).all(-1) & (blocks == blocks[..., :1]).all(-1)
    # Texel centres: the sub-point nearest the centre, on its triangle (barycentric interpolation).
    c = sub // 2
    tri = tri_of[c::sub, c::sub]
    centre = np.zeros((size, size, 3))
    normal = np.zeros((size, size, 3))
    ys, xs = np.nonzero(interior)
    for y, x in zip(ys, xs):
        t = tri[y, x]
        uv, w = mesh["uv1"][t], mesh["tris"][t]
        q = np.array([(x + 0.5) / size, (y + 0.5) / size])
        m = np.array([uv[1] - uv[0], uv[2] - uv[0]]).T
        b1, b2 = np.linalg.solve(m, q - uv[0])
        centre[y, x] = w[0] + b1 * (w[1] - w[0]) + b2 * (w[2] - w[0])
        ng = np.cross(w[1] - w[0], w[2] - w[0])
        normal[y, x] = ng / np.linalg.norm(ng)
    return interior, centre, normal


def leak_fraction(points, normals, scene_tris, k=64, seed=7):
    """Fraction of k cosine-distributed directions (stratified) from each point whose first hit is a back face
    (geometric normal . direction > 0), as kelvin's leak test has it (at any distance)."""
    rng = np.random.default_rng(seed)
    g = int(math.sqrt(k))
    u = (np.stack(np.meshgrid(np.arange(g), np.arange(g)), -1).reshape(-1, 2) + rng.random((g * g, 2))) / g
    r, phi = np.sqrt(u[:, 0]), 2 * math.pi * u[:, 1]
    local = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(0, 1 - u[:, 0]))], -1)
    v0, e1, e2 = scene_tris[:, 0], scene_tris[:, 1] - scene_tris[:, 0], scene_tris[:, 2] - scene_tris[:, 0]
    ng = np.cross(e1, e2)
    scale = np.abs(scene_tris).max()
    eps = 1e-5 * scale
    out = np.zeros(len(points))
    for s in range(0, len(points), 256):
        p, n = points[s:s + 256], normals[s:s + 256]
        a = np.where(np.abs(n[:, :1]) < 0.9, np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
        t1 = np.cross(n, a)
        t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
        t2 = np.cross(n, t1)
        d = local[None, :, :1] * t1[:, None] + local[None, :, 1:2] * t2[:, None] + local[None, :, 2:] * n[:, None]
        o = (p + n * eps)[:, None, :]
        # Moller-Trumbore, rays (P, k) x triangles (T).
        D = d[:, :, None, :]
        pv = np.cross(D, e2)
        det = (e1 * pv).sum(-1)
        inv = np.where(np.abs(det) > 1e-20, 1.0 / np.where(det == 0, 1, det), 0.0)
        tv = o[:, :, None, :] - v0
        uu = (tv * pv).sum(-1) * inv
        qv = np.cross(tv, e1)
        vv = (D * qv).sum(-1) * inv
        tt = (e2 * qv).sum(-1) * inv
        hit = (inv != 0) & (uu >= 0) & (vv >= 0) & (uu + vv <= 1) & (tt > eps)
        tt = np.where(hit, tt, np.inf)
        first = tt.argmin(-1)
        any_hit = np.isfinite(tt.min(-1))
        back = (ng[first] * d).sum(-1) > 0
        out[s:s + 256] = (any_hit & back).mean(-1)
    return out


def stats(mask, k, k2, kr, c, c2, ref):
    k, k2, kr, c, c2, ref = (x[mask] for x in (k, k2, kr, c, c2, ref))
    rmse = lambda x, y: float(np.sqrt(((x - y) ** 2).mean()))  # noqa: E731
    def div(x, y):  # the leak zone can be all zeros in Cycles, the lamp's own map at depth 1 in both
        return float(x / y) if y > 0 else (math.nan if x == 0 else math.inf)
    r = {"texels": int(mask.sum()), "mean_k_c": div(k.sum(), c.sum()),
         "mean_k_c_rgb": [div(x, y) for x, y in zip(k.sum(0), c.sum(0))],
         "mean_kref_cref": div(kr.sum(), ref.sum()),
         "mean_kref_cref_rgb": [div(x, y) for x, y in zip(kr.sum(0), ref.sum(0))],
         "mean_c_ref": div(c.sum(), ref.sum()), "rmse_k": rmse(k, ref), "rmse_c": rmse(c, ref),
         "noise_k": rmse(k, k2) / math.sqrt(2), "noise_c": rmse(c, c2) / math.sqrt(2),
         "relmse_k": div(((k - ref) ** 2).sum(), (ref ** 2).sum()),
         "relmse_c": div(((c - ref) ** 2).sum(), (ref ** 2).sum()), "ref_mean": float(ref.mean()),
         "kref_mean": float(kr.mean())}
    r["rmse_k_over_c"] = div(r["rmse_k"], r["rmse_c"])
    r["rmse_k_over_noise"] = div(r["rmse_k"], r["noise_k"])
    r["rmse_c_over_noise"] = div(r["rmse_c"], r["noise_c"])
    return r


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kelvin", default="/tmp/kbin/kelvin-main")
    ap.add_argument("--cycles-python", default=sys.executable)
    ap.add_argument("--scene", default=str(REPO / "tests" / "data" / "gltf" / "bevy" / "CornellBox.glb"))
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--spp", type=int, default=32)
    ap.add_argument("--ref-mult", type=int, default=16)
    ap.add_argument("--depths", default="16,1")
    ap.add_argument("--albedo-floor", type=float, default=1e-4)
    ap.add_argument("--two-sided-emitters", action="store_true",
                    help="keep the file's doubleSided on emitters (kelvin) and Cycles' two-sided emission")
    ap.add_argument("--out-dir", default="/tmp/peers/cycles_bake")
    ap.add_argument("--json-out", default=None)
    ap.add_argument("--reuse", action="store_true", help="reuse finished bakes in --out-dir")
    ap.add_argument("--speed-rounds", type=int, default=0,
                    help="then R alternating rounds of kelvin and Cycles at N spp (seeds 10+): best-of times")
    a = ap.parse_args(argv)
    out = Path(a.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    # The scene both bake.
    doc, binary, glb = read_gltf(a.scene)
    sided = [m.get("doubleSided", False) for m in doc.get("materials", [])]
    changes = lambertian(doc)
    if a.two_sided_emitters:
        for i, (m, was) in enumerate(zip(doc.get("materials", []), sided)):
            if was and not m.get("doubleSided", False):
                m["doubleSided"] = True
                changes.append(f"material {i} '{m.get('name', '')}': doubleSided -> true again (--two-sided-emitters)")
    for i, m in enumerate(doc.get("materials", [])):
        pbr = m.setdefault("pbrMetallicRoughness", {})
        f = pbr.get("baseColorFactor", [1, 1, 1, 1])
        if a.albedo_floor > 0 and min(f[:3]) <= 0:
            pbr["baseColorFactor"] = [max(x, a.albedo_floor) for x in f[:3]] + list(f[3:])
            changes.append(f"material {i} '{m.get('name', '')}': base colour {f[:3]} -> "
                           f"{pbr['baseColorFactor'][:3]} (albedo floor)")
    scene = out / ("bake_" + Path(a.scene).stem + ".glb")
    write_glb(scene, doc, binary)
    for c in changes:
        print(f"scene: {c}", file=sys.stderr)
    meshes = [m for m in gltf_meshes(scene) if m["uv1"] is not None]
    names = [m["name"] for m in meshes]
    if len(set(names)) != len(names):
        raise SystemExit("a mesh placed twice: not handled (kelvin and bake_cycles.py name the files differently)")
    scene_tris = np.concatenate([m["tris"] for m in gltf_meshes(scene)])
    masks = {}
    for m in meshes:
        interior, centre, normal = interior_texels(m, a.size)
        leak = np.zeros((a.size, a.size))
        leak[interior] = leak_fraction(centre[interior], normal[interior], scene_tris)
        masks[m["name"]] = {"interior": interior, "clean": interior & (leak == 0), "zone": interior & (leak > 0)}
    from bake_cycles import load_exr_rgb
    results = {"conditions": {**vars(a), "scene_baked": str(scene), "changes": changes}, "rows": []}
    for d in (int(x) for x in a.depths.split(",")):
        tag = out / f"d{d}"
        N, M = a.spp, a.spp * a.ref_mult
        runs = {"k": kelvin_bake(a, scene, d, N, 0, tag / "kelvin_s0"),
                "k2": kelvin_bake(a, scene, d, N, 1, tag / "kelvin_s1"),
                "c": cycles_bake(a, scene, d, N, 1, tag / "cycles_s1"),
                "c2": cycles_bake(a, scene, d, N, 3, tag / "cycles_s3"),
                "kr": kelvin_bake(a, scene, d, M, 2, tag / "kelvin_ref"),
                "ref": cycles_bake(a, scene, d, M, 2, tag / "cycles_ref")}
        dirs = {"k": "kelvin_s0", "k2": "kelvin_s1", "c": "cycles_s1", "c2": "cycles_s3", "kr": "kelvin_ref",
                "ref": "cycles_ref"}
        pooled = {key: [] for key in runs}
        pooled_mask = []
        rows = []
        for name in names:
            imgs = {key: load_exr_rgb(tag / dirs[key] / runs[key]["files"][name]) for key in runs}
            for key in runs:
                pooled[key].append(imgs[key])
            pooled_mask.append(masks[name]["clean"])
            row = {"depth": d, "cycles_bounces": d - 1, "mesh": name, "spp": N, "ref_spp": M}
            for what in ("clean", "zone"):
                if masks[name][what].any():
                    row[what] = stats(masks[name][what], *(imgs[key] for key in ("k", "k2", "kr", "c", "c2", "ref")))
            rows.append(row)
        all_ = stats(np.concatenate(pooled_mask), *(np.concatenate(pooled[key]) for key in
                                                     ("k", "k2", "kr", "c", "c2", "ref")))
        rows.append({"depth": d, "cycles_bounces": d - 1, "mesh": "all", "spp": N, "ref_spp": M, "clean": all_})
        tk, tc = runs["k"]["seconds"], runs["c"]["seconds"]
        # CPU seconds (all threads): kelvin's whole process (loading and writing are ~1% of it), Cycles' bake call.
        ck, cc = runs["k"]["cpu"], runs["c"].get("bake_cpu") or runs["c"]["cpu"]
        timing = {"k": [runs["k"]], "c": [runs["c"]]}
        for i in range(a.speed_rounds):
            timing["k"].append(kelvin_bake(a, scene, d, N, 10 + i, tag / f"speed_kelvin_{i}"))
            timing["c"].append(cycles_bake(a, scene, d, N, 10 + i, tag / f"speed_cycles_{i}"))
        if a.speed_rounds:
            tk, tc = min(r["seconds"] for r in timing["k"]), min(r["seconds"] for r in timing["c"])
            ck = min(r["cpu"] for r in timing["k"])
            cc = min(r.get("bake_cpu") or r["cpu"] for r in timing["c"])
        results.setdefault("timing", {})[f"d{d}"] = {
            "kelvin_seconds": tk, "cycles_seconds": tc, "kelvin_cpu": ck, "cycles_cpu": cc,
            "rounds": {key: [{f: r.get(f) for f in ("seconds", "wall", "cpu", "bake_cpu", "load_before")}
                             for r in v] for key, v in timing.items()}}
        for row in rows:
            s = row["clean"]
            ok = s["relmse_k"] > 0 and s["noise_k"] > 0  # not a map of zeros (the lamp's own at depth 1)
            s["speed_equal_noise"] = (tc * s["relmse_c"]) / (tk * s["relmse_k"]) if ok else math.nan
            s["speed_equal_noise_cpu"] = (cc * s["relmse_c"]) / (ck * s["relmse_k"]) if ok else math.nan
            s["speed_equal_noise_2seed"] = (tc * s["noise_c"] ** 2) / (tk * s["noise_k"] ** 2) if ok else math.nan
        results["rows"] += rows
        results.setdefault("runs", {})[f"d{d}"] = runs
        best = f"best of {a.speed_rounds + 1} runs" if a.speed_rounds else "one run"
        print(f"depth {d} (Cycles bounces {d - 1}), {a.size}x{a.size}, {N} spp, reference Cycles {M} spp: "
              f"kelvin {tk:.2f} s (CPU {ck:.1f} s), Cycles {tc:.2f} s (CPU {cc:.1f} s), {best}; load average "
              f"before the runs {min(r['load_before'] for v in timing.values() for r in v):.1f}-"
              f"{max(r['load_before'] for v in timing.values() for r in v):.1f}", flush=True)
        print("mesh         texels  mean k/c  k/c @ref spp  RMSE k/c  k/noise  c/noise  relMSE k   relMSE c   "
              "speed@eq.noise (2-seed)  | leak zone: texels, mean k/c@ref")
        for row in rows:
            s, z = row["clean"], row.get("zone")
            zs = f"{z['texels']:6d} {z['mean_kref_cref']:.3f}" if z else "     0"
            print(f"{row['mesh']:12s} {s['texels']:6d}  {s['mean_k_c']:.4f}   {s['mean_kref_cref']:.4f}       "
                  f"{s['rmse_k_over_c']:.3f}     {s['rmse_k_over_noise']:.3f}    {s['rmse_c_over_noise']:.3f}    "
                  f"{s['relmse_k']:.3e}  {s['relmse_c']:.3e}  {s['speed_equal_noise']:.2f}x ({s['speed_equal_noise_2seed']:.2f}x, CPU {s['speed_equal_noise_cpu']:.2f}x)"
                  f"  | {zs}", flush=True)
    if a.json_out:
        Path(a.json_out).write_text(json.dumps(results, indent=1, default=str) + "\n")


if __name__ == "__main__":
    main()
