#!/usr/bin/env python3
"""Bake a lightmap per mesh of a glTF file with Blender Cycles (CPU), as `kelvin bake lightmaps` does.

    /tmp/cycles-venv/bin/python bench/cycles/bake_cycles.py SCENE.glb|.gltf -o DIR [--size 256] [--spp 128]
        [--max-depth 16] [--seed 0] [--margin 4] [--uv-index 1] [--emission-sides gltf|two] [--threads 0]
        [--lighting-mode COMPAT] [--json]

Writes DIR/<mesh>.exr per baked mesh (linear float RGB, 32-bit, rows top to bottom as glTF's uv: v = 0 is the
first row, as kelvin's) and DIR/cycles_bake.json; with --json also prints that JSON as the last line.

  * Scene: cycles_gltf.py's setup (Blender's glTF importer with lighting mode COMPAT, black world, punctual
    lights of radius 0, no clamping/denoising/adaptive sampling/light threshold, tabulated Sobol), so the units
    are kelvin's (README.md beside this file).
  * What is baked: bake_type DIFFUSE with pass_filter {DIRECT, INDIRECT} and no COLOR: Cycles divides the
    diffuse light by the diffuse colour, i.e. the radiance a white Lambertian surface would reflect, E/pi, which
    is kelvin's texel (check_bake_units.py checks it against the closed form of a point light). Where a
    material's diffuse colour is 0 in a channel, Cycles' division gives 0 in that channel (a warning is printed;
    compare_bake.py gives such channels a tiny albedo in the file both bake).
  * Target: a new float image of --size per mesh object whose glTF mesh has TEXCOORD_<uv-index> (the importer's
    uv_layers[uv-index], made the active and render UV map), an Image Texture node made active in each of the
    object's materials (materials are made single-user first, so meshes that share one bake into their own
    image), all meshes in one bpy.ops.object.bake call. Margin --margin texels, type EXTEND (kelvin dilates 4).
  * Depth: --max-depth is kelvin's (surfaces after the texel's own; 1 = direct light); Cycles counts bounces after
    the first hit, so its max/diffuse/glossy/transmission bounces are --max-depth - 1, as in a render.
  * Emission: Cycles emits from both sides of every surface. --emission-sides gltf (default) makes the emission
    of materials with glTF doubleSided false (the importer's use_backface_culling) front-only, by multiplying
    the emission strength by 1 - Geometry.Backfacing and sampling the front only (emission_sampling FRONT), as
    kelvin (and scripts/make_lambertian_copy.py's emitters) have it; `two` leaves Cycles' two-sided emission.
  * Orientation: Blender's importer stores v_blender = 1 - v_gltf and Blender images are stored bottom row
    first; Blender writes an EXR top row first, so the EXR's first row is v_blender = 1, i.e. v_gltf = 0, as
    kelvin's (check_bake_units.py checks it with an off-centre light).
Timing: `bake_seconds` is the wall time of bpy.ops.object.bake (scene sync, BVH, baking and writing the
images' buffers; not the import nor the EXR files), `bake_cpu_seconds` the CPU time (all threads, user + system)
of the same call, `total_seconds` the script's wall time from before the import.
"""
import argparse
import json
import os
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("-o", "--output", required=True, help="output folder")
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--spp", type=int, default=128)
    ap.add_argument("--max-depth", type=int, default=16, help="kelvin's --max-depth (Cycles bounces = this - 1)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--margin", type=int, default=4, help="bake margin, texels (EXTEND)")
    ap.add_argument("--uv-index", type=int, default=1, help="glTF TEXCOORD_n to bake into (default 1)")
    ap.add_argument("--emission-sides", choices=["gltf", "two"], default="gltf")
    ap.add_argument("--lighting-mode", choices=["SPEC", "COMPAT", "RAW"], default="COMPAT")
    ap.add_argument("--threads", type=int, default=0, help="0: all cores")
    ap.add_argument("--json", action="store_true", help="print the JSON summary as the last line")
    a = ap.parse_args(argv)
    if a.max_depth < 1:
        ap.error("--max-depth must be >= 1")
    return a


def load_exr_rgb(path):
    """An EXR read with Blender's image loader -> float64 array (H, W, 3), first row = the file's first row.
    Needs bpy (the Cycles venv); works for kelvin's and this script's files alike."""
    import bpy
    import numpy as np
    img = bpy.data.images.load(str(path), check_existing=False)
    try:
        img.colorspace_settings.name = "Non-Color"  # no conversion on load (EXR data is linear already)
        w, h = img.size
        buf = np.empty(w * h * 4, np.float32)
        img.pixels.foreach_get(buf)
        # Blender's buffer is bottom row first: flip to the file's order.
        return buf.reshape(h, w, 4)[::-1, :, :3].astype(np.float64)
    finally:
        bpy.data.images.remove(img)


def one_sided_emission(bpy, mat):
    """Emission strength x (1 - Backfacing) on the material's Principled BSDF(s); -> True if changed."""
    nt = mat.node_tree
    changed = False
    for p in [n for n in nt.nodes if n.type == "BSDF_PRINCIPLED"]:
        s = p.inputs["Emission Strength"]
        if s.is_linked or s.default_value == 0.0:
            if s.is_linked:
                raise SystemExit(f"material {mat.name}: linked emission strength not handled")
            continue
        geo = nt.nodes.new("ShaderNodeNewGeometry")
        front = nt.nodes.new("ShaderNodeMath")
        front.operation = "SUBTRACT"
        front.inputs[0].default_value = 1.0
        nt.links.new(geo.outputs["Backfacing"], front.inputs[1])
        mul = nt.nodes.new("ShaderNodeMath")
        mul.operation = "MULTIPLY"
        mul.inputs[1].default_value = s.default_value
        nt.links.new(front.outputs[0], mul.inputs[0])
        nt.links.new(mul.outputs[0], s)
        changed = True
    if changed:
        mat.cycles.emission_sampling = "FRONT"
    return changed


def prepare_targets(bpy, a, notes):
    """Per mesh object with the uv map: a float image, an active Image Texture node in each (single-user)
    material. -> list of (object, image, file name)."""
    scene = bpy.context.scene
    targets, used = [], set()
    for ob in sorted((o for o in scene.objects if o.type == "MESH"), key=lambda o: o.name):
        uvs = ob.data.uv_layers
        if len(uvs) <= a.uv_index:
            notes.append(f"{ob.name}: no uv map {a.uv_index} (TEXCOORD_{a.uv_index}); skipped")
            continue
        uvs.active = uvs[a.uv_index]
        uvs[a.uv_index].active_render = True
        name = ob.data.name  # the importer names the mesh datablock after the glTF mesh
        while name in used:
            name = name + "." + ob.name
        used.add(name)
        img = bpy.data.images.new(f"bake_{name}", a.size, a.size, alpha=False, float_buffer=True)
        img.colorspace_settings.name = "Linear Rec.709"
        for slot in ob.material_slots:
            if slot.material is None:
                raise SystemExit(f"{ob.name}: a face without a material")
            if slot.material.users > 1:
                slot.material = slot.material.copy()
            mat = slot.material
            nt = mat.node_tree
            node = nt.nodes.new("ShaderNodeTexImage")
            node.image = img
            node.name = "kelvin_bake_target"
            for n in nt.nodes:
                n.select = False
            node.select = True
            nt.nodes.active = node
        targets.append((ob, img, name))
    return targets


def zero_albedo_channels(bpy, targets, notes):
    for ob, _, _ in targets:
        for slot in ob.material_slots:
            for p in [n for n in slot.material.node_tree.nodes if n.type == "BSDF_PRINCIPLED"]:
                c = p.inputs["Base Color"]
                if not c.is_linked and min(c.default_value[:3]) <= 0.0:
                    notes.append(f"{ob.name} material {slot.material.name}: base colour {tuple(c.default_value[:3])} "
                                 "has a zero channel: Cycles' DIFFUSE no-colour bake is 0 in that channel")


def main(argv=None):
    a = parse_args(argv)
    t_start = time.perf_counter()
    import bpy  # noqa: E402
    import mathutils  # noqa: E402
    import cycles_gltf  # noqa: E402

    notes = []
    out = Path(a.output)
    out.mkdir(parents=True, exist_ok=True)
    ra = cycles_gltf.parse_args([a.scene, "--size", f"{a.size}x{a.size}", "--spp", str(a.spp), "--max-depth",
                                 str(a.max_depth), "--seed", str(a.seed), "--lighting-mode", a.lighting_mode,
                                 "--threads", str(a.threads), "--out", str(out / "unused.exr")])
    scene = cycles_gltf.setup(bpy, mathutils, ra, notes)
    one_sided = []
    if a.emission_sides == "gltf":
        for mat in bpy.data.materials:
            if mat.use_backface_culling and mat.node_tree and one_sided_emission(bpy, mat):
                one_sided.append(mat.name)
    targets = prepare_targets(bpy, a, notes)
    if not targets:
        raise SystemExit(f"{a.scene}: no mesh with uv map {a.uv_index}")
    zero_albedo_channels(bpy, targets, notes)
    bake = scene.render.bake
    bake.margin, bake.margin_type = a.margin, "EXTEND"
    bake.use_clear, bake.target, bake.use_selected_to_active = True, "IMAGE_TEXTURES", False
    for ob in scene.objects:
        ob.select_set(False)
    for ob, _, _ in targets:
        ob.select_set(True)
    bpy.context.view_layer.objects.active = targets[0][0]
    load_s = time.perf_counter() - t_start
    t0, cpu0 = time.perf_counter(), time.process_time()
    bpy.ops.object.bake(type="DIFFUSE", pass_filter={"DIRECT", "INDIRECT"}, margin=a.margin, margin_type="EXTEND",
                        use_clear=True, target="IMAGE_TEXTURES")
    bake_s, bake_cpu = time.perf_counter() - t0, time.process_time() - cpu0
    s = scene.render.image_settings
    s.file_format, s.color_depth, s.color_mode, s.exr_codec = "OPEN_EXR", "32", "RGB", "ZIP"
    files = {}
    for ob, img, name in targets:
        path = out / f"{name}.exr"
        img.save_render(str(path), scene=scene)
        files[name] = {"object": ob.name, "mesh": ob.data.name, "exr": path.name}
    total_s = time.perf_counter() - t_start
    for n in notes:
        print(f"note: {n}", file=sys.stderr)
    summary = {"scene": os.path.abspath(a.scene), "size": a.size, "spp": a.spp, "max_depth": a.max_depth,
               "cycles_bounces": a.max_depth - 1, "seed": a.seed, "margin": a.margin, "uv_index": a.uv_index,
               "emission_sides": a.emission_sides, "one_sided_emission": one_sided,
               "bake_seconds": bake_s, "bake_cpu_seconds": bake_cpu, "load_seconds": load_s, "total_seconds": total_s,
               "threads": scene.render.threads, "sampling_pattern": scene.cycles.sampling_pattern,
               "blender": bpy.app.version_string, "lightmaps": files, "notes": notes}
    (out / "cycles_bake.json").write_text(json.dumps(summary, indent=1) + "\n")
    print(f"cycles {bpy.app.version_string} CPU bake of {len(targets)} lightmaps of {a.size}x{a.size} at {a.spp} spp, "
          f"bounces {a.max_depth - 1}: {bake_s:.3f} s (bake), {total_s:.3f} s in all; wrote {out}", flush=True)
    if a.json:
        print(json.dumps(summary), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
