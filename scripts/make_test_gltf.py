#!/usr/bin/env python3
"""Writes kelvin's own small glTF test files into tests/data/gltf/kelvin/ (Python 3 standard library only).

    python3 scripts/make_test_gltf.py

Every file is a .gltf whose geometry sits in one base64 data: URI buffer, so it needs nothing beside it except
what it names on purpose (the EXT_lights_ies file references a real IES profile elsewhere in tests/data). The
output is deterministic: running the script again rewrites the same bytes. What each file is for, and what the
tests read from it, is in tests/data/SOURCES.md and tests/gltf_import.rs.

Conventions (glTF 2.0): right-handed, +Y up, metres; a triangle's front face is counter-clockwise, its geometric
normal (p1 - p0) x (p2 - p0). The script checks the facing of every surface it writes, in world space and with the
spec's rule that a node whose world transform has a negative determinant reverses the winding (section 3.7.4).
"""

import base64
import json
import math
import struct
from pathlib import Path

OUT = Path(__file__).resolve().parent.parent / "tests" / "data" / "gltf" / "kelvin"

# glTF constants.
FLOAT, UNSIGNED_SHORT = 5126, 5123
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963


def sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def normalize(v):
    n = math.sqrt(sum(x * x for x in v))
    return [x / n for x in v]


def quad(corner, edge_u, edge_v):
    """Four corners corner, +u, +u+v, +v: triangles (0, 1, 2), (0, 2, 3) face (edge_u x edge_v)."""
    c, u, v = corner, edge_u, edge_v
    return [c, [c[i] + u[i] for i in range(3)], [c[i] + u[i] + v[i] for i in range(3)], [c[i] + v[i] for i in range(3)]]


QUAD_INDICES = [0, 1, 2, 0, 2, 3]


class Gltf:
    """A glTF document under construction: one buffer, meshes of one triangle-list primitive each."""

    def __init__(self):
        self.bin = bytearray()
        self.doc = {
            "asset": {"version": "2.0", "generator": "kelvin scripts/make_test_gltf.py"},
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

    def material(self, **fields):
        self.doc["materials"].append(fields)
        return len(self.doc["materials"]) - 1

    def mesh(self, name, positions, indices, material):
        """A mesh without NORMAL data (its facing is the winding alone)."""
        data = b"".join(struct.pack("<3f", *p) for p in positions)
        pos = self._accessor(
            bufferView=self._view(data, ARRAY_BUFFER),
            componentType=FLOAT,
            count=len(positions),
            type="VEC3",
            min=[min(p[i] for p in positions) for i in range(3)],
            max=[max(p[i] for p in positions) for i in range(3)],
        )
        idx = self._accessor(
            bufferView=self._view(struct.pack(f"<{len(indices)}H", *indices), ELEMENT_ARRAY_BUFFER),
            componentType=UNSIGNED_SHORT,
            count=len(indices),
            type="SCALAR",
        )
        primitive = {"attributes": {"POSITION": pos}, "indices": idx, "material": material}
        self.doc["meshes"].append({"name": name, "primitives": [primitive]})
        return len(self.doc["meshes"]) - 1

    def node(self, **fields):
        self.doc["nodes"].append(fields)
        self.doc["scenes"][0]["nodes"].append(len(self.doc["nodes"]) - 1)
        return len(self.doc["nodes"]) - 1

    def write(self, name):
        if not self.doc["materials"]:
            del self.doc["materials"]
        uri = "data:application/octet-stream;base64," + base64.b64encode(bytes(self.bin)).decode("ascii")
        self.doc["buffers"] = [{"byteLength": len(self.bin), "uri": uri}]
        OUT.mkdir(parents=True, exist_ok=True)
        text = json.dumps(self.doc, indent=2) + "\n"
        (OUT / name).write_text(text, encoding="utf-8")
        print(f"wrote {OUT / name} ({len(text)} bytes)")


def floor(g, half_size):
    """A grey floor at y = 0, facing up, `half_size` metres each way from the origin."""
    s = half_size
    positions = quad([-s, 0.0, -s], [0.0, 0.0, 2 * s], [2 * s, 0.0, 0.0])
    assert normalize(cross(sub(positions[1], positions[0]), sub(positions[2], positions[0]))) == [0.0, 1.0, 0.0]
    grey = g.material(
        name="floor", pbrMetallicRoughness={"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0}
    )
    return g.node(name="floor", mesh=g.mesh("floor", positions, QUAD_INDICES, grey))


# ---- ies_light_colour.gltf ----

# A rotation of -90 degrees about +X: the light's local -Z (an IES profile's nadir) points down, world -Y.
AIM_DOWN = [-math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)]


def ies_light_colour():
    """Two EXT_lights_ies downlights with the real profile ASA_15M_R2.ies (LuxCore's test file, referenced by a
    relative uri, not copied), 3 m over a floor: "lamp_coloured" (multiplier 2.5, colour [1, 0.5, 0.25]) at the
    origin, "lamp_black" (multiplier 2.5, colour [0, 0, 0]) 4 m along +X."""
    g = Gltf()
    floor(g, 6.0)
    g.doc["extensionsUsed"] = ["EXT_lights_ies"]
    g.doc["extensions"] = {"EXT_lights_ies": {"lights": [{"uri": "../../ies/luxcore/ASA_15M_R2.ies"}]}}
    for name, x, colour in [("lamp_coloured", 0.0, [1.0, 0.5, 0.25]), ("lamp_black", 4.0, [0.0, 0.0, 0.0])]:
        g.node(
            name=name,
            translation=[x, 3.0, 0.0],
            rotation=AIM_DOWN,
            extensions={"EXT_lights_ies": {"light": 0, "multiplier": 2.5, "color": colour}},
        )
    assert (OUT.parent.parent / "ies" / "luxcore" / "ASA_15M_R2.ies").is_file(), "the profile the file names"
    g.write("ies_light_colour.gltf")


# ---- mirrored_emitter.gltf and its unmirrored twin ----


def front_normals(positions, indices, scale):
    """World-space unit front normals of the triangles under a node `scale`, with the winding reversed when the
    scale's determinant is negative (glTF 2.0 spec, section 3.7.4)."""
    world = [[p[i] * scale[i] for i in range(3)] for p in positions]
    out = []
    for t in range(0, len(indices), 3):
        a, b, c = (world[i] for i in indices[t : t + 3])
        if scale[0] * scale[1] * scale[2] < 0:
            b, c = c, b
        out.append(normalize(cross(sub(b, a), sub(c, a))))
    return out


def mirror_x(positions):
    return [[-p[0], p[1], p[2]] for p in positions]


def reverse_winding(indices):
    return [i for t in range(0, len(indices), 3) for i in (indices[t], indices[t + 2], indices[t + 1])]


MIRROR = [-1.0, 1.0, 1.0]


def mirrored_emitter(mirrored):
    """A 4 x 4 m floor at y = 0; over it a one-sided emissive 1 x 1 m quad at y = 1 (centred over the origin,
    4 nits, facing down, no NORMAL data) and a 0.4 x 0.4 m occluder at y = 0.5 over x in [-0.5, -0.1].

    `mirrored`: the emitter's and the occluder's nodes have scale [-1, 1, 1] and their meshes are written in the
    mirror image (the occluder's local x in [0.1, 0.5]), facing down in their own frame. A loader following the
    spec (negative determinant: winding reversed) finds them facing down in the world too; one that keeps the
    winding finds them facing up, and the one-sided emitter lights the sky. Otherwise (the twin): the same
    world-space surfaces without any node transform. The two files light the floor alike."""
    g = Gltf()
    floor(g, 2.0)
    g.doc["extensionsUsed"] = ["KHR_materials_emissive_strength"]
    glow = g.material(
        name="emitter",
        pbrMetallicRoughness={"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0},
        emissiveFactor=[1.0, 1.0, 1.0],
        extensions={"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}},
    )
    grey = g.material(name="occluder", pbrMetallicRoughness={"baseColorFactor": [0.5, 0.5, 0.5, 1.0]})
    # World space, facing down: (edge_u x edge_v) = (1, 0, 0) x (0, 0, 1) = -Y.
    emitter = quad([-0.5, 1.0, -0.5], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0])
    occluder = quad([-0.5, 0.5, -0.2], [0.4, 0.0, 0.0], [0.0, 0.0, 0.4])
    for name, positions, material in [("emitter", emitter, glow), ("occluder", occluder, grey)]:
        assert front_normals(positions, QUAD_INDICES, [1.0, 1.0, 1.0]) == [[0.0, -1.0, 0.0]] * 2
        if mirrored:
            # The mirror image, wound to face down in its own frame; the node's mirror puts it back in place, and
            # by 3.7.4 it still faces down. Keeping the winding through the mirror would make it face up.
            local, indices = mirror_x(positions), reverse_winding(QUAD_INDICES)
            assert front_normals(local, indices, [1.0, 1.0, 1.0]) == [[0.0, -1.0, 0.0]] * 2
            assert front_normals(local, indices, MIRROR) == [[0.0, -1.0, 0.0]] * 2
            kept = front_normals([[p[i] * MIRROR[i] for i in range(3)] for p in local], indices, [1.0, 1.0, 1.0])
            assert kept == [[0.0, 1.0, 0.0]] * 2
            g.node(name=name, mesh=g.mesh(name, local, indices, material), scale=MIRROR)
        else:
            g.node(name=name, mesh=g.mesh(name, positions, QUAD_INDICES, material))
    g.write("mirrored_emitter.gltf" if mirrored else "unmirrored_emitter.gltf")


# ---- animated_lamp.gltf ----


def animated_lamp():
    """Node animation with a closed-form value per frame (tests/render_animation.rs). Over a 6 x 6 m Lambertian
    floor (base colour 0.5, KHR_materials_specular factor 0) for t in [0, 2] s:

    * "rig" (root): translation STEP, x = 0 before t = 1 and 0.6 from then; scale CUBICSPLINE from 1 to 2 with
      zero tangents, s(t) = 1 + 3u^2 - 2u^3, u = t / 2.
    * "lamp" (child of rig): a 10 cd white KHR_lights_punctual point light; translation LINEAR from (0, 1, 0) to
      (0, 2, 0). Its world position is (rig x, s(t) (1 + t / 2), 0).
    * "shutter": a grey 0.8 x 0.8 m quad at y = 0.5 facing up, translation LINEAR from x = 3 to x = -3, over the
      origin at t = 1, where it shadows the point the camera looks at.
    * "camera": yfov 0.01 rad at (0, 3, 3) looking at the floor point (cx, 0, 0); translation LINEAR moves cx
      from 0 to 0.4.
    """
    g = Gltf()
    g.doc["extensionsUsed"] = ["KHR_lights_punctual", "KHR_materials_specular"]
    g.doc["extensions"] = {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 10.0, "name": "lamp"}]}}
    s = 3.0
    positions = quad([-s, 0.0, -s], [0.0, 0.0, 2 * s], [2 * s, 0.0, 0.0])
    lambert = g.material(
        name="floor",
        pbrMetallicRoughness={"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0},
        extensions={"KHR_materials_specular": {"specularFactor": 0.0}},
    )
    g.node(name="floor", mesh=g.mesh("floor", positions, QUAD_INDICES, lambert))
    shutter_quad = quad([-0.4, 0.0, -0.4], [0.0, 0.0, 0.8], [0.8, 0.0, 0.0])
    assert normalize(cross(sub(shutter_quad[1], shutter_quad[0]), sub(shutter_quad[2], shutter_quad[0]))) == [0, 1, 0]
    shutter = g.node(name="shutter", mesh=g.mesh("shutter", shutter_quad, QUAD_INDICES, lambert), translation=[3.0, 0.5, 0.0])
    rig = g.node(name="rig", children=[])
    lamp = len(g.doc["nodes"])
    g.doc["nodes"].append({"name": "lamp", "translation": [0.0, 1.0, 0.0], "extensions": {"KHR_lights_punctual": {"light": 0}}})
    g.doc["nodes"][rig]["children"].append(lamp)
    # Looking along (0, -1, -1): -Z turned down by 45 degrees, a rotation of -45 degrees about +X.
    look = [-math.sin(math.pi / 8), 0.0, 0.0, math.cos(math.pi / 8)]
    g.doc["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.01, "znear": 0.01}}]
    camera = g.node(name="camera", camera=0, translation=[0.0, 3.0, 3.0], rotation=look)

    def floats(values, kind):
        flat = [x for v in values for x in (v if isinstance(v, list) else [v])]
        view = g._view(struct.pack(f"<{len(flat)}f", *flat), None)
        g.doc["bufferViews"][view].pop("target")
        extra = {"min": [min(values)], "max": [max(values)]} if kind == "SCALAR" else {}
        return g._accessor(bufferView=view, componentType=FLOAT, count=len(values), type=kind, **extra)

    samplers, channels = [], []

    def channel(node, path, times, values, interpolation):
        samplers.append({"input": floats(times, "SCALAR"), "output": floats(values, "VEC3"), "interpolation": interpolation})
        channels.append({"sampler": len(samplers) - 1, "target": {"node": node, "path": path}})

    channel(rig, "translation", [0.0, 1.0], [[0.0, 0.0, 0.0], [0.6, 0.0, 0.0]], "STEP")
    # In-tangent, value, out-tangent per keyframe.
    channel(rig, "scale", [0.0, 2.0], [[0.0] * 3, [1.0] * 3, [0.0] * 3, [0.0] * 3, [2.0] * 3, [0.0] * 3], "CUBICSPLINE")
    channel(lamp, "translation", [0.0, 2.0], [[0.0, 1.0, 0.0], [0.0, 2.0, 0.0]], "LINEAR")
    channel(shutter, "translation", [0.0, 2.0], [[3.0, 0.5, 0.0], [-3.0, 0.5, 0.0]], "LINEAR")
    channel(camera, "translation", [0.0, 2.0], [[0.0, 3.0, 3.0], [0.4, 3.0, 3.0]], "LINEAR")
    g.doc["animations"] = [{"name": "day", "samplers": samplers, "channels": channels}]
    g.write("animated_lamp.gltf")


if __name__ == "__main__":
    animated_lamp()
    ies_light_colour()
    mirrored_emitter(True)
    mirrored_emitter(False)
