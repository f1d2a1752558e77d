#!/usr/bin/env python3
"""Adds a node animation to a .glb (Python 3 standard library only), for measuring what a frame of animation costs.

    python3 scripts/animate_gltf.py IN.glb OUT.glb [--every K] [--offset DX,DY,DZ] [--seconds S]

Every K-th root node of the default scene that has a mesh or a light gets a LINEAR translation channel from its
rest translation to rest + offset over S seconds (one clip, "moved"). Nothing else in the file changes.
"""

import argparse
import json
import struct

FLOAT = 5126


def read_glb(path):
    data = open(path, "rb").read()
    magic, version, _ = struct.unpack_from("<4sII", data, 0)
    if magic != b"glTF" or version != 2:
        raise SystemExit(f"{path}: not a glTF 2.0 .glb")
    offset, doc, binary = 12, None, b""
    while offset < len(data):
        length, kind = struct.unpack_from("<I4s", data, offset)
        chunk = data[offset + 8 : offset + 8 + length]
        if kind == b"JSON":
            doc = json.loads(chunk)
        elif kind == b"BIN\0":
            binary = bytearray(chunk)
        offset += 8 + length
    return doc, bytearray(binary)


def write_glb(path, doc, binary):
    while len(binary) % 4:
        binary.append(0)
    doc["buffers"][0]["byteLength"] = len(binary)
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    total = 12 + 8 + len(text) + 8 + len(binary)
    with open(path, "wb") as f:
        f.write(struct.pack("<4sII", b"glTF", 2, total))
        f.write(struct.pack("<I4s", len(text), b"JSON") + text)
        f.write(struct.pack("<I4s", len(binary), b"BIN\0") + bytes(binary))


def main():
    p = argparse.ArgumentParser()
    p.add_argument("input")
    p.add_argument("output")
    p.add_argument("--every", type=int, default=1)
    p.add_argument("--offset", default="0,0.1,0")
    p.add_argument("--seconds", type=float, default=1.0)
    opts = p.parse_args()
    offset = [float(x) for x in opts.offset.split(",")]
    doc, binary = read_glb(opts.input)
    if len(doc.get("buffers", [])) != 1 or "uri" in doc["buffers"][0]:
        raise SystemExit(f"{opts.input}: only a .glb whose one buffer is its BIN chunk is handled")

    def accessor(values, kind):
        while len(binary) % 4:
            binary.append(0)
        flat = [x for v in values for x in (v if isinstance(v, list) else [v])]
        doc.setdefault("bufferViews", []).append(
            {"buffer": 0, "byteOffset": len(binary), "byteLength": 4 * len(flat)}
        )
        binary.extend(struct.pack(f"<{len(flat)}f", *flat))
        extra = {"min": [min(values)], "max": [max(values)]} if kind == "SCALAR" else {}
        doc.setdefault("accessors", []).append(
            {"bufferView": len(doc["bufferViews"]) - 1, "componentType": FLOAT, "count": len(values), "type": kind, **extra}
        )
        return len(doc["accessors"]) - 1

    times = accessor([0.0, opts.seconds], "SCALAR")
    roots = doc["scenes"][doc.get("scene", 0)]["nodes"]
    movable = [n for n in roots if "mesh" in doc["nodes"][n] or "extensions" in doc["nodes"][n]]
    samplers, channels = [], []
    for n in movable[:: opts.every]:
        node = doc["nodes"][n]
        if "matrix" in node:
            continue
        rest = node.get("translation", [0.0, 0.0, 0.0])
        moved = [rest[i] + offset[i] for i in range(3)]
        samplers.append({"input": times, "output": accessor([rest, moved], "VEC3"), "interpolation": "LINEAR"})
        channels.append({"sampler": len(samplers) - 1, "target": {"node": n, "path": "translation"}})
    doc.setdefault("animations", []).append({"name": "moved", "samplers": samplers, "channels": channels})
    write_glb(opts.output, doc, binary)
    print(f"wrote {opts.output}: {len(channels)} of {len(movable)} nodes with a mesh or a light animated")


if __name__ == "__main__":
    main()
