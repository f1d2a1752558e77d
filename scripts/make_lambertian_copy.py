#!/usr/bin/env python3
"""Write a copy of a glTF 2.0 file (.glb or .gltf) whose materials are Lambertian and whose emitters are one-sided.

    python3 scripts/make_lambertian_copy.py [--emitters-only] IN.glb|IN.gltf OUT.glb|OUT.gltf

Why: to compare kelvin's path tracer with Mitsuba 3 on the same scene. Mitsuba's `principled` BSDF is not
glTF's BRDF, and Mitsuba's area lights emit from the front face only, so both sides are made to agree:
  * every material: pbrMetallicRoughness.metallicFactor 0, metallicRoughnessTexture removed (no metal from a
    texture either), KHR_materials_specular {specularFactor: 0} (no specular lobe: base colour x Lambert),
    other material extensions (clearcoat, sheen, transmission, ...) removed; KHR_materials_emissive_strength
    is kept; baseColor factor and texture, normals and alpha are kept;
  * every emissive material (emissiveFactor > 0 or an emissiveTexture): doubleSided false (front face only);
  * "KHR_materials_specular" is added to extensionsUsed.
With --emitters-only, only the emitters are made one-sided and the materials are left as they are (to compare
glTF's own BRDF, e.g. with bench/mitsuba/gltf_bsdf.py).
The output keeps the input's form (.glb in, .glb out; .gltf in, .gltf out). For a .gltf written to another
folder, the external buffers and images it names are copied beside it under the same relative paths.
Standard library only. Prints one line per changed material.
"""
import json
import os
import shutil
import struct
import sys
import urllib.parse

KEEP_EXTENSIONS = {"KHR_materials_emissive_strength", "KHR_materials_specular"}
GLB_MAGIC, JSON_CHUNK, BIN_CHUNK = 0x46546C67, 0x4E4F534A, 0x004E4942


def read_gltf(path):
    """-> (json dict, bin chunk bytes or None, is_glb)"""
    with open(path, "rb") as f:
        data = f.read()
    if data[:4] != b"glTF":
        return json.loads(data.decode("utf-8-sig")), None, False
    magic, version, length = struct.unpack_from("<III", data, 0)
    if version != 2:
        raise SystemExit(f"{path}: GLB version {version}, 2 needed")
    doc, binary, off = None, None, 12
    while off + 8 <= min(length, len(data)):
        n, kind = struct.unpack_from("<II", data, off)
        chunk = data[off + 8:off + 8 + n]
        if kind == JSON_CHUNK:
            doc = json.loads(chunk.decode("utf-8"))
        elif kind == BIN_CHUNK and binary is None:
            binary = chunk
        off += 8 + n
    if doc is None:
        raise SystemExit(f"{path}: GLB without a JSON chunk")
    return doc, binary, True


def write_glb(path, doc, binary):
    js = json.dumps(doc, separators=(",", ":")).encode("utf-8")
    js += b" " * (-len(js) % 4)
    chunks = struct.pack("<II", len(js), JSON_CHUNK) + js
    if binary is not None:
        b = bytes(binary) + b"\0" * (-len(binary) % 4)
        chunks += struct.pack("<II", len(b), BIN_CHUNK) + b
    with open(path, "wb") as f:
        f.write(struct.pack("<III", GLB_MAGIC, 2, 12 + len(chunks)) + chunks)


def is_emissive(m):
    return any(float(c) > 0 for c in m.get("emissiveFactor", [0, 0, 0])) or "emissiveTexture" in m


def one_sided_emitters(doc):
    changes = []
    for i, m in enumerate(doc.get("materials", [])):
        if is_emissive(m) and m.get("doubleSided", False):
            m["doubleSided"] = False
            changes.append(f"material {i} '{m.get('name', '')}': emissive: doubleSided -> false")
    return changes


def lambertian(doc):
    """Edits doc's materials in place; -> list of change descriptions."""
    changes = []
    for i, m in enumerate(doc.get("materials", [])):
        name, what = m.get("name", f"material{i}"), []
        pbr = m.setdefault("pbrMetallicRoughness", {})
        if pbr.get("metallicFactor", 1.0) != 0:
            what.append(f"metallic {pbr.get('metallicFactor', 1.0)} -> 0")
        pbr["metallicFactor"] = 0.0
        if pbr.pop("metallicRoughnessTexture", None) is not None:
            what.append("metallicRoughnessTexture removed")
        ext = m.setdefault("extensions", {})
        for e in sorted(set(ext) - KEEP_EXTENSIONS):
            del ext[e]
            what.append(f"{e} removed")
        if ext.get("KHR_materials_specular") != {"specularFactor": 0.0}:
            what.append("specularFactor -> 0")
        ext["KHR_materials_specular"] = {"specularFactor": 0.0}
        if is_emissive(m) and m.get("doubleSided", False):
            m["doubleSided"] = False
            what.append("emissive: doubleSided -> false")
        changes.append(f"material {i} '{name}': " + (", ".join(what) if what else "already Lambertian"))
    used_by_materials = {e for m in doc.get("materials", []) for e in m.get("extensions", {})}
    material_ext = lambda e: e.startswith("KHR_materials_")  # noqa: E731
    used = [e for e in doc.get("extensionsUsed", []) if not material_ext(e) or e in used_by_materials]
    doc["extensionsUsed"] = used + sorted(used_by_materials - set(used))
    if "extensionsRequired" in doc:
        req = [e for e in doc["extensionsRequired"] if not material_ext(e) or e in used_by_materials]
        if req:
            doc["extensionsRequired"] = req
        else:
            del doc["extensionsRequired"]
    return changes


def copy_external(doc, src_dir, dst_dir):
    """Copy the buffers and images a .gltf names by relative URI from src_dir to dst_dir."""
    if os.path.abspath(src_dir) == os.path.abspath(dst_dir):
        return
    for item in doc.get("buffers", []) + doc.get("images", []):
        uri = item.get("uri")
        if not uri or uri.startswith("data:") or "://" in uri:
            continue
        rel = urllib.parse.unquote(uri)
        src, dst = os.path.join(src_dir, rel), os.path.join(dst_dir, rel)
        if os.path.isfile(src) and not os.path.exists(dst):
            os.makedirs(os.path.dirname(dst) or ".", exist_ok=True)
            shutil.copyfile(src, dst)


def main(argv):
    emitters_only = "--emitters-only" in argv
    argv = [x for x in argv if x != "--emitters-only"]
    if len(argv) != 2 or argv[0] in ("-h", "--help"):
        print(__doc__)
        return 0 if argv and argv[0] in ("-h", "--help") else 2
    src, dst = argv
    doc, binary, glb = read_gltf(src)
    if not str(doc.get("asset", {}).get("version", "")).startswith("2."):
        raise SystemExit(f"{src}: not a glTF 2.x file")
    if glb != dst.lower().endswith(".glb"):
        raise SystemExit(f"{dst}: give the same form as the input ({'.glb' if glb else '.gltf'})")
    for line in (one_sided_emitters(doc) if emitters_only else lambertian(doc)):
        print(line)
    os.makedirs(os.path.dirname(os.path.abspath(dst)), exist_ok=True)
    if glb:
        write_glb(dst, doc, binary)
    else:
        copy_external(doc, os.path.dirname(os.path.abspath(src)), os.path.dirname(os.path.abspath(dst)))
        with open(dst, "w") as f:
            json.dump(doc, f, indent=1)
    print(f"wrote {dst}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
