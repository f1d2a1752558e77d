#!/usr/bin/env python3
"""Closed-form check of the lightmap convention of `kelvin bake lightmaps` and of bake_cycles.py (Cycles'
DIFFUSE bake, DIRECT + INDIRECT, no COLOR): units, the white-albedo division, and the rows' orientation.

    /tmp/cycles-venv/bin/python bench/cycles/check_bake_units.py [--kelvin /tmp/kbin/kelvin-main] [--size 64]
        [--spp 64] [--out-dir /tmp/peers/cycles_bake_units]

The scene (written by this script as a .gltf): a 2 m x 2 m quad at y = 0 facing +Y (doubleSided), base colour
(0.8, 0.5, 0.0) (a zero channel on purpose), TEXCOORD_1 u = 0.1 + 0.4 (x + 1), v = 0.1 + 0.4 (z + 1) (the chart
fills [0.1, 0.9]^2), and a KHR_lights_punctual point light of I = 10 cd at (0.5, 1, -0.5), off-centre in both
u and v, so a flip of either axis moves the bright spot. Both bake at depth 1 (direct light). Expected texel:
E / pi with E = I h / r^3 (h = 1 m), averaged over the texel (4x4 points), on the texels the chart covers fully,
row 0 = v 0 (glTF's uv, as kelvin writes). Prints per renderer: mean ratio to the closed form per channel,
RMS relative error, and the texel of the maximum against the closed form's.
"""
import argparse
import base64
import json
import math
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

I_CD, LIGHT = 10.0, (0.5, 1.0, -0.5)
COLOUR = [0.8, 0.5, 0.0, 1.0]


def uv1(x, z):
    return 0.1 + 0.4 * (x + 1.0), 0.1 + 0.4 * (z + 1.0)


def write_scene(path):
    # Corners (x, z): front face +Y needs counter-clockwise seen from above: (-1,1),(1,1),(1,-1),(-1,-1).
    xz = [(-1.0, 1.0), (1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)]
    pos = [(x, 0.0, z) for x, z in xz]
    n = [(0.0, 1.0, 0.0)] * 4
    uv = [uv1(x, z) for x, z in xz]
    idx = [0, 1, 2, 0, 2, 3]
    e1, e2 = np.subtract(pos[1], pos[0]), np.subtract(pos[2], pos[0])
    assert np.cross(e1, e2)[1] > 0, "the quad must face +Y"
    blobs = [b"".join(struct.pack("<3f", *p) for p in pos), b"".join(struct.pack("<3f", *p) for p in n),
             b"".join(struct.pack("<2f", *p) for p in uv), struct.pack("<6H", *idx) + b"\0\0"]
    views, off = [], 0
    for b in blobs:
        views.append({"buffer": 0, "byteOffset": off, "byteLength": len(b)})
        off += len(b)
    data = b"".join(blobs)
    acc = [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
            "min": [-1.0, 0.0, -1.0], "max": [1.0, 0.0, 1.0]},
           {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
           {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
           {"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"}]
    doc = {
        "asset": {"version": "2.0", "generator": "kelvin bench/cycles/check_bake_units.py"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": I_CD, "color": [1, 1, 1]}]}},
        "scene": 0, "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"name": "quad", "mesh": 0},
                  {"name": "lamp", "translation": list(LIGHT), "extensions": {"KHR_lights_punctual": {"light": 0}}}],
        "meshes": [{"name": "quad", "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2,
                                                                   "TEXCOORD_1": 2}, "indices": 3, "material": 0}]}],
        "materials": [{"name": "orange", "doubleSided": True,
                       "pbrMetallicRoughness": {"baseColorFactor": COLOUR, "metallicFactor": 0.0},
                       "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}}],
        "accessors": acc, "bufferViews": views,
        "buffers": [{"byteLength": len(data),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
    }
    doc["extensionsUsed"].append("KHR_materials_specular")
    path.write_text(json.dumps(doc, indent=1))


def closed_form(size, sub=4):
    """-> (size, size) E/pi averaged over each texel (4x4 points), and the mask of fully covered texels.
    Row r, column c: v in [r, r+1]/size (row 0 = v 0), u in [c, c+1]/size."""
    t = (np.arange(size * sub) + 0.5) / (size * sub)
    u, v = np.meshgrid(t, t)  # v varies along rows
    x, z = (u - 0.1) / 0.4 - 1.0, (v - 0.1) / 0.4 - 1.0
    inside = (np.abs(x) <= 1) & (np.abs(z) <= 1)
    h = LIGHT[1]
    r2 = (x - LIGHT[0]) ** 2 + h * h + (z - LIGHT[2]) ** 2
    e = I_CD * h / r2 ** 1.5 / math.pi
    e = np.where(inside, e, 0.0).reshape(size, sub, size, sub).mean((1, 3))
    full = inside.reshape(size, sub, size, sub).all((1, 3))
    return e, full


def run(cmd):
    cmd = [str(c) for c in cmd]
    print("$ " + " ".join(cmd), file=sys.stderr, flush=True)
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        sys.stderr.write(p.stdout + p.stderr)
        raise SystemExit(f"failed (exit {p.returncode}): {cmd[0]}")
    return p.stdout


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kelvin", default="/tmp/kbin/kelvin-main")
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--out-dir", default="/tmp/peers/cycles_bake_units")
    a = ap.parse_args(argv)
    out = Path(a.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    scene = out / "quad_point_light.gltf"
    write_scene(scene)
    run([a.kelvin, "bake", "lightmaps", scene, "-o", out / "kelvin", "--size", a.size, "--spp", a.spp,
         "--max-depth", 1])
    run([sys.executable, HERE / "bake_cycles.py", scene, "-o", out / "cycles", "--size", a.size, "--spp", a.spp,
         "--max-depth", 1])
    from bake_cycles import load_exr_rgb
    expect, full = closed_form(a.size)
    peak = np.unravel_index(np.argmax(np.where(full, expect, 0)), expect.shape)
    ok = True
    for name in ("kelvin", "cycles"):
        img = load_exr_rgb(out / name / "quad.exr")
        got = img[full]
        ratio = got.mean(0) / expect[full].mean()
        rel = np.sqrt((((got - expect[full][:, None]) / expect[full][:, None]) ** 2).mean(0))
        lum = np.where(full, img[..., 0], 0)
        their_peak = np.unravel_index(np.argmax(lum), lum.shape)
        print(f"{name}: mean / closed form R {ratio[0]:.4f} G {ratio[1]:.4f} B {ratio[2]:.4f}; RMS rel. error "
              f"{'/'.join(f'{x:.4f}' for x in rel)}; brightest texel (row, col) {tuple(int(i) for i in their_peak)}, "
              f"closed form's {tuple(int(i) for i in peak)}")
        ok &= bool(abs(ratio[0] - 1) < 0.01 and abs(ratio[1] - 1) < 0.01)
        ok &= max(abs(their_peak[0] - peak[0]), abs(their_peak[1] - peak[1])) <= 2
    print("ok" if ok else "MISMATCH (see above)")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
