#!/usr/bin/env python3
"""Writes the render suite's generated glTF scenes into tests/data/gltf/bench/ (Python 3 standard library only).

    python3 scripts/make_bench_gltf.py

The files are .glb (one JSON chunk, one binary chunk), deterministic: running the script again rewrites the same
bytes. `kelvin bench render` (src/report/render_bench.rs) renders them beside the real files of tests/data, and
bench/mitsuba/compare.py renders the same files with Mitsuba 3. The suite's scaling scene (scaling_10k.glb) is
not written here but by `cargo run --example export_scaling_gltf`, since its layout is drawn from kelvin's own
random-number stream.

  sphere_65k.glb     a UV sphere of 65,536 triangles (smooth normals) over a 12 x 12 m floor, one point light
                     (300 cd), a camera.
  env_objects.glb    three boxes and three spheres on a 30 x 30 m floor, no light (the suite lights it with
                     tests/data/env/spiaggia_di_mondello_1k.hdr, as `kelvin render --env` does), a camera.

Every material is Lambertian in both kelvin and the Mitsuba script: metallic 0, roughness 1 and
KHR_materials_specular specularFactor 0 (kelvin then drops the specular lobe; Mitsuba's converter makes it a
`diffuse` BSDF). Conventions (glTF 2.0): right-handed, +Y up, metres; a triangle's front face is
counter-clockwise. The script checks that every triangle faces out of its solid (or up, for the floors).
"""

import json
import math
import struct
from pathlib import Path

OUT = Path(__file__).resolve().parent.parent / "tests" / "data" / "gltf" / "bench"

# glTF constants.
FLOAT, UNSIGNED_SHORT, UNSIGNED_INT = 5126, 5123, 5125
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963


def sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def add(a, b):
    return [a[i] + b[i] for i in range(3)]


def dot(a, b):
    return sum(a[i] * b[i] for i in range(3))


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def normalize(v):
    n = math.sqrt(dot(v, v))
    return [x / n for x in v]


def look_at_quaternion(eye, target, up=(0.0, 1.0, 0.0)):
    """Unit quaternion [x, y, z, w] turning a glTF camera (looking down -Z, +Y up) to look from eye at target."""
    z = normalize(sub(eye, target))  # the camera's +Z points away from what it looks at
    x = normalize(cross(list(up), z))
    y = cross(z, x)
    # Rotation matrix with columns x, y, z -> quaternion (Shepperd's method, the largest-diagonal branch).
    m = [[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]]
    trace = m[0][0] + m[1][1] + m[2][2]
    if trace > 0.0:
        s = 2.0 * math.sqrt(1.0 + trace)
        q = [(m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s, 0.25 * s]
    elif m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        s = 2.0 * math.sqrt(1.0 + m[0][0] - m[1][1] - m[2][2])
        q = [0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s, (m[2][1] - m[1][2]) / s]
    elif m[1][1] > m[2][2]:
        s = 2.0 * math.sqrt(1.0 + m[1][1] - m[0][0] - m[2][2])
        q = [(m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s, (m[0][2] - m[2][0]) / s]
    else:
        s = 2.0 * math.sqrt(1.0 + m[2][2] - m[0][0] - m[1][1])
        q = [(m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s, (m[1][0] - m[0][1]) / s]
    n = math.sqrt(sum(c * c for c in q))
    q = [c / n for c in q]
    # Check: the rotated -Z is the viewing direction.
    forward = rotate(q, [0.0, 0.0, -1.0])
    assert dot(forward, normalize(sub(target, eye))) > 1.0 - 1e-9
    return [round(c, 9) for c in q]


def rotate(q, v):
    """v rotated by the unit quaternion q = [x, y, z, w]."""
    u, w = q[:3], q[3]
    t = [2.0 * c for c in cross(u, v)]
    return add(add(v, [w * c for c in t]), cross(u, t))


class Glb:
    """A glTF document under construction with one binary buffer; meshes of one triangle-list primitive each."""

    def __init__(self, generator_note):
        self.bin = bytearray()
        self.doc = {
            "asset": {"version": "2.0", "generator": f"kelvin scripts/make_bench_gltf.py ({generator_note})"},
            "extensionsUsed": ["KHR_materials_specular"],
            "scene": 0,
            "scenes": [{"nodes": []}],
            "nodes": [],
            "meshes": [],
            "materials": [],
            "accessors": [],
            "bufferViews": [],
            "buffers": [],
        }

    def _view(self, data, target):
        while len(self.bin) % 4:
            self.bin.append(0)
        self.doc["bufferViews"].append(
            {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data), "target": target}
        )
        self.bin.extend(data)
        return len(self.doc["bufferViews"]) - 1

    def _accessor(self, **fields):
        self.doc["accessors"].append(fields)
        return len(self.doc["accessors"]) - 1

    def lambertian(self, name, rgb):
        """A Lambertian material of albedo rgb (see the module doc)."""
        self.doc["materials"].append(
            {
                "name": name,
                "pbrMetallicRoughness": {
                    "baseColorFactor": [*rgb, 1.0],
                    "metallicFactor": 0.0,
                    "roughnessFactor": 1.0,
                },
                "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}},
            }
        )
        return len(self.doc["materials"]) - 1

    def mesh(self, name, positions, normals, indices, material):
        """A mesh with POSITION, NORMAL and indices (u16 when they fit, else u32)."""
        assert len(positions) == len(normals) and len(indices) % 3 == 0
        flat = [c for p in positions for c in p]
        pos = self._accessor(
            bufferView=self._view(struct.pack(f"<{len(flat)}f", *flat), ARRAY_BUFFER),
            componentType=FLOAT,
            count=len(positions),
            type="VEC3",
            # min/max of the float32 values actually stored (the spec asks for exact bounds).
            min=[min(struct.unpack("<f", struct.pack("<f", p[i]))[0] for p in positions) for i in range(3)],
            max=[max(struct.unpack("<f", struct.pack("<f", p[i]))[0] for p in positions) for i in range(3)],
        )
        flat_n = [c for n in normals for c in n]
        nrm = self._accessor(
            bufferView=self._view(struct.pack(f"<{len(flat_n)}f", *flat_n), ARRAY_BUFFER),
            componentType=FLOAT,
            count=len(normals),
            type="VEC3",
        )
        small = len(positions) <= 65535
        fmt, component = ("H", UNSIGNED_SHORT) if small else ("I", UNSIGNED_INT)
        idx = self._accessor(
            bufferView=self._view(struct.pack(f"<{len(indices)}{fmt}", *indices), ELEMENT_ARRAY_BUFFER),
            componentType=component,
            count=len(indices),
            type="SCALAR",
        )
        primitive = {"attributes": {"POSITION": pos, "NORMAL": nrm}, "indices": idx, "material": material}
        self.doc["meshes"].append({"name": name, "primitives": [primitive]})
        return len(self.doc["meshes"]) - 1

    def node(self, **fields):
        self.doc["nodes"].append(fields)
        self.doc["scenes"][0]["nodes"].append(len(self.doc["nodes"]) - 1)
        return len(self.doc["nodes"]) - 1

    def camera(self, name, eye, target, yfov_deg):
        self.doc.setdefault("cameras", []).append(
            {"name": name, "type": "perspective", "perspective": {"yfov": math.radians(yfov_deg), "znear": 0.01}}
        )
        cam = len(self.doc["cameras"]) - 1
        return self.node(name=name, camera=cam, translation=list(eye), rotation=look_at_quaternion(eye, target))

    def point_light(self, name, position, intensity_cd, colour=(1.0, 1.0, 1.0)):
        self.doc["extensionsUsed"].append("KHR_lights_punctual")
        ext = self.doc.setdefault("extensions", {}).setdefault("KHR_lights_punctual", {"lights": []})
        ext["lights"].append({"name": name, "type": "point", "color": list(colour), "intensity": intensity_cd})
        light = len(ext["lights"]) - 1
        return self.node(name=name, translation=list(position), extensions={"KHR_lights_punctual": {"light": light}})

    def write(self, name):
        while len(self.bin) % 4:
            self.bin.append(0)
        self.doc["buffers"] = [{"byteLength": len(self.bin)}]
        self.doc["extensionsUsed"] = sorted(set(self.doc["extensionsUsed"]))
        text = json.dumps(self.doc, separators=(",", ":")).encode("utf-8")
        text += b" " * (-len(text) % 4)
        body = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(self.bin), 0x004E4942)
        body += bytes(self.bin)
        data = struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body
        OUT.mkdir(parents=True, exist_ok=True)
        (OUT / name).write_bytes(data)
        print(f"wrote {OUT / name} ({len(data)} bytes)")


def check_outward(positions, indices, inside):
    """Every triangle's front (counter-clockwise) normal points away from the point `inside`."""
    for t in range(0, len(indices), 3):
        a, b, c = (positions[i] for i in indices[t : t + 3])
        n = cross(sub(b, a), sub(c, a))
        centroid = [(a[i] + b[i] + c[i]) / 3.0 for i in range(3)]
        assert dot(n, sub(centroid, inside)) > 0.0, f"triangle {t // 3} faces inward"


def uv_sphere(centre, radius, slices, stacks):
    """A UV sphere: (stacks + 1) x (slices + 1) vertices, smooth normals, 2 slices (stacks - 1) triangles (one per
    cell in the two polar rings, two elsewhere), all facing out."""
    positions, normals = [], []
    for i in range(stacks + 1):
        theta = math.pi * i / stacks
        for j in range(slices + 1):
            phi = 2.0 * math.pi * j / slices
            n = [math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi)]
            if i in (0, stacks):
                n = [0.0, 1.0 if i == 0 else -1.0, 0.0]
            normals.append(n)
            positions.append([centre[k] + radius * n[k] for k in range(3)])
    indices = []
    row = slices + 1
    for i in range(stacks):
        for j in range(slices):
            a, b, c, d = i * row + j, i * row + j + 1, (i + 1) * row + j, (i + 1) * row + j + 1
            # a-b on ring i (phi increasing, counter-clockwise seen from above), c-d on ring i + 1 below it.
            if i != 0:
                indices += [a, c, b]
            if i != stacks - 1:
                indices += [b, c, d]
    check_outward(positions, indices, centre)
    assert len(indices) // 3 == 2 * slices * (stacks - 1)
    return positions, normals, indices


def box(centre, half):
    """An axis-aligned box: 6 faces of 2 triangles, flat normals, facing out."""
    positions, normals, indices = [], [], []
    for axis in range(3):
        for sign in (1.0, -1.0):
            n = [0.0, 0.0, 0.0]
            n[axis] = sign
            u, v = [0.0] * 3, [0.0] * 3
            u[(axis + 1) % 3] = 1.0
            v[(axis + 2) % 3] = 1.0
            if sign < 0:
                u, v = v, u  # keep u x v = n
            base = len(positions)
            for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                positions.append([centre[k] + half[k] * (n[k] + su * u[k] + sv * v[k]) for k in range(3)])
                normals.append(n)
            indices += [base, base + 1, base + 2, base, base + 2, base + 3]
    check_outward(positions, indices, centre)
    return positions, normals, indices


def floor(g, half_size, albedo):
    """A floor at y = 0, facing up, `half_size` metres each way from the origin."""
    s = half_size
    positions = [[-s, 0.0, -s], [-s, 0.0, s], [s, 0.0, s], [s, 0.0, -s]]
    indices = [0, 1, 2, 0, 2, 3]
    check_outward(positions, indices, [0.0, -1.0, 0.0])
    normals = [[0.0, 1.0, 0.0]] * 4
    return g.node(name="floor", mesh=g.mesh("floor", positions, normals, indices, g.lambertian("floor", albedo)))


def sphere_65k():
    """A 65,536-triangle UV sphere (256 slices x 129 stacks, radius 1 m, resting on the floor) over a 12 x 12 m
    floor, lit by one white point light of 300 cd at (3, 5, 2): the sphere's shadow falls on the floor in view."""
    g = Glb("sphere_65k")
    floor(g, 6.0, [0.8, 0.8, 0.8])
    positions, normals, indices = uv_sphere([0.0, 1.0, 0.0], 1.0, 256, 129)
    assert len(indices) // 3 == 65536
    g.node(name="sphere", mesh=g.mesh("sphere", positions, normals, indices, g.lambertian("sphere", [0.7, 0.3, 0.2])))
    g.point_light("point", [3.0, 5.0, 2.0], 300.0)
    g.camera("camera", [0.0, 3.0, 7.0], [0.0, 0.7, 0.0], 45.0)
    g.write("sphere_65k.glb")


def env_objects():
    """Three boxes and three spheres (48 slices x 24 stacks) of different albedos on a 30 x 30 m floor; no light
    in the file (the environment map lights it), a camera looking down at them from the front."""
    g = Glb("env_objects")
    floor(g, 15.0, [0.5, 0.5, 0.5])
    boxes = [
        ([-1.6, 0.5, -0.4], [0.5, 0.5, 0.5], [0.8, 0.8, 0.8]),
        ([0.9, 0.75, -1.3], [0.4, 0.75, 0.4], [0.2, 0.4, 0.8]),
        ([2.0, 0.25, 0.9], [0.6, 0.25, 0.35], [0.8, 0.6, 0.2]),
    ]
    for k, (c, h, rgb) in enumerate(boxes):
        p, n, i = box(c, h)
        g.node(name=f"box{k}", mesh=g.mesh(f"box{k}", p, n, i, g.lambertian(f"box{k}", rgb)))
    spheres = [
        ([0.0, 0.6, 0.6], 0.6, [0.9, 0.9, 0.9]),
        ([-0.7, 0.35, 1.8], 0.35, [0.8, 0.2, 0.2]),
        ([1.2, 0.45, 2.3], 0.45, [0.2, 0.7, 0.3]),
    ]
    for k, (c, r, rgb) in enumerate(spheres):
        p, n, i = uv_sphere(c, r, 48, 24)
        g.node(name=f"sphere{k}", mesh=g.mesh(f"sphere{k}", p, n, i, g.lambertian(f"sphere{k}", rgb)))
    g.camera("camera", [0.5, 2.6, 6.5], [0.2, 0.4, 0.3], 45.0)
    g.write("env_objects.glb")


if __name__ == "__main__":
    sphere_65k()
    env_objects()
