#!/usr/bin/env python3
"""Render a glTF 2.0 file with Blender Cycles (CPU) to a linear float EXR, with the settings of a path-tracer
comparison.

    /tmp/cycles-venv/bin/python bench/cycles/cycles_gltf.py SCENE.glb|.gltf [--size 128x128] [--spp 64]
        [--max-depth 5] [--seed 0] [--out OUT.exr] [--filter-width 1.0] [--lighting-mode COMPAT]
        [--sampling-pattern TABULATED_SOBOL] [--distribution MULTI_GGX|GGX] [--threads 0] [--json]

Needs the `bpy` wheel (pip install bpy==5.0.1 in a Python 3.11 venv, see README.md beside this file).
  * Import: Blender's own glTF importer (bpy.ops.import_scene.gltf) into an empty file, with --lighting-mode:
    COMPAT ("Unitless", default) makes a point/spot light of I cd a Blender light of 4*pi*I W and a directional
    light of E lux a sun of strength E, so that Cycles' radiance is kelvin's nits (1 cd = 1 W/sr, 1 lux = 1 W/m^2);
    SPEC ("Standard") divides those by 683 lm/W; RAW copies the numbers. Emission is not converted in any mode:
    emissiveFactor x KHR_materials_emissive_strength becomes the emission strength, i.e. nits. Punctual lights get
    radius 0 (glTF lights are points). World: black, or nothing else lights the scene.
  * Camera: the file's first camera (its yfov, vertical fit); without one, kelvin's and mitsuba_gltf.py's framing
    camera (yfov 45 deg, from glTF +Z and 0.35 up, around the bounding sphere of the geometry's box).
  * Bounces: --max-depth is kelvin's (surfaces after the camera's, 1 = direct lighting). Cycles counts bounces
    after the first hit (0 bounces = direct lighting), so max/diffuse/glossy/transmission bounces = depth - 1.
  * No clamping (sample_clamp_direct/indirect 0), no denoiser, no adaptive sampling, no light threshold, no
    glossy filter, view transform Standard (the EXR is linear scene-referred anyway), linear Rec.709 = sRGB.
  * Pixel filter: Cycles importance-samples a Blackman-Harris filter of --filter-width pixels (min 0.01, which
    is a point sample at the pixel centre); width 1 keeps the samples inside the pixel like a box filter.
Timing: the wall time of bpy.ops.render.render (scene sync, BVH build and rendering); printed, and in --json.
"""
import argparse
import json
import math
import os
import struct
import sys
import time


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--size", default="128x128")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--max-depth", type=int, default=5, help="kelvin's --max-depth (Cycles bounces = this - 1)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default="cycles.exr")
    ap.add_argument("--filter-width", type=float, default=1.0, help="pixel filter width in pixels (default 1)")
    ap.add_argument("--lighting-mode", choices=["SPEC", "COMPAT", "RAW"], default="COMPAT")
    ap.add_argument("--sampling-pattern", default="TABULATED_SOBOL",
                    help="Cycles sampling pattern (default TABULATED_SOBOL; AUTOMATIC uses blue noise)")
    ap.add_argument("--distribution", choices=["MULTI_GGX", "GGX"], default=None,
                    help="set every Principled BSDF's distribution (default: the importer's, multiscatter GGX)")
    ap.add_argument("--threads", type=int, default=0, help="0: all cores")
    ap.add_argument("--json", action="store_true", help="print a JSON line last")
    a = ap.parse_args(argv)
    a.width, a.height = (int(x) for x in a.size.lower().split("x"))
    if a.max_depth < 1:
        ap.error("--max-depth must be >= 1 (Cycles has no emission-only mode)")
    return a


def gltf_json(path):
    with open(path, "rb") as f:
        data = f.read()
    if data[:4] == b"glTF":
        n = struct.unpack_from("<I", data, 12)[0]
        return json.loads(data[20:20 + n].decode("utf-8"))
    return json.loads(data.decode("utf-8-sig"))


def to_blender(v):
    """glTF (Y up) -> Blender (Z up), as Blender's importer converts."""
    return (v[0], -v[2], v[1])


def framing_camera(bpy, mathutils, notes):
    """kelvin's / mitsuba_gltf.py's camera for files without one (computed in glTF axes)."""
    lo, hi = [math.inf] * 3, [-math.inf] * 3
    for ob in bpy.context.scene.objects:
        if ob.type != "MESH":
            continue
        for v in ob.data.vertices:
            w = ob.matrix_world @ v.co
            g = (w.x, w.z, -w.y)  # Blender -> glTF
            lo, hi = [min(a, b) for a, b in zip(lo, g)], [max(a, b) for a, b in zip(hi, g)]
    centre = [(a + b) / 2 for a, b in zip(lo, hi)]
    radius = max(math.dist(lo, hi) / 2, 1e-3)
    yfov = math.radians(45.0)
    n = math.hypot(0.35, 1.0)
    d = (0.0, 0.35 / n, 1.0 / n)
    dist = radius / math.sin(yfov / 2) * 1.1
    origin = [c + dist * x for c, x in zip(centre, d)]
    cam = bpy.data.cameras.new("framing")
    ob = bpy.data.objects.new("framing", cam)
    bpy.context.scene.collection.objects.link(ob)
    ob.location = to_blender(origin)
    fwd = mathutils.Vector(to_blender([-x for x in d]))
    ob.rotation_euler = fwd.to_track_quat("-Z", "Y").to_euler()
    cam.sensor_fit, cam.angle_y = "VERTICAL", yfov
    cam.clip_start, cam.clip_end = dist * 1e-3, 10 * (dist + radius)
    notes.append(f"no camera in the file: framing camera at {dist:.4g} from the box centre "
                 f"{[round(c, 4) for c in centre]} (glTF axes)")
    return ob


def setup(bpy, mathutils, a, notes):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=os.path.abspath(a.scene), export_import_convert_lighting_mode=a.lighting_mode)
    scene = bpy.context.scene
    doc = gltf_json(a.scene)
    cams = [ob for ob in scene.objects if ob.type == "CAMERA"]
    if cams:
        cam_ob = cams[0]
        persp = [c for c in doc.get("cameras", []) if c.get("type") == "perspective"]
        if persp:  # the file's yfov, vertical fit, whatever aspect ratio the importer set
            cam_ob.data.sensor_fit, cam_ob.data.angle_y = "VERTICAL", persp[0]["perspective"]["yfov"]
        cam_ob.data.clip_end = max(cam_ob.data.clip_end, 1e4)
        if len(cams) > 1:
            notes.append(f"{len(cams)} cameras: '{cam_ob.name}' is used")
    else:
        cam_ob = framing_camera(bpy, mathutils, notes)
    scene.camera = cam_ob
    for ob in scene.objects:
        if ob.type == "LIGHT":
            ob.data.shadow_soft_size = 0.0
            if ob.data.type == "SUN":
                ob.data.angle = 0.0
    if a.distribution:
        for mat in bpy.data.materials:
            for node in (mat.node_tree.nodes if mat.node_tree else []):
                if node.type == "BSDF_PRINCIPLED":
                    node.distribution = a.distribution
    world = bpy.data.worlds.new("black")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    scene.world = world

    r, c = scene.render, scene.cycles
    r.engine = "CYCLES"
    c.device = "CPU"
    r.resolution_x, r.resolution_y, r.resolution_percentage = a.width, a.height, 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.threads_mode = "FIXED" if a.threads else "AUTO"
    if a.threads:
        r.threads = a.threads
    c.samples, c.seed, c.use_animated_seed = a.spp, a.seed, False
    c.use_adaptive_sampling, c.use_denoising, c.use_preview_denoising = False, False, False
    for vl in scene.view_layers:
        vl.cycles.use_denoising = False
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    c.light_sampling_threshold, c.blur_glossy = 0.0, 0.0
    b = a.max_depth - 1
    c.max_bounces = c.diffuse_bounces = c.glossy_bounces = c.transmission_bounces = b
    c.volume_bounces, c.transparent_max_bounces = 0, 64
    c.min_light_bounces, c.min_transparent_bounces = 0, 0
    c.filter_width = max(a.filter_width, 0.01)
    try:
        c.sampling_pattern = a.sampling_pattern
    except TypeError as e:
        notes.append(f"sampling pattern {a.sampling_pattern} not available ({e}); Cycles' default kept")
    r.film_transparent = False
    vs = scene.view_settings
    vs.view_transform, vs.look, vs.exposure, vs.gamma = "Standard", "None", 0.0, 1.0
    scene.display_settings.display_device = "sRGB"
    s = r.image_settings
    s.file_format, s.color_depth, s.color_mode, s.exr_codec = "OPEN_EXR", "32", "RGB", "ZIP"
    r.filepath = os.path.abspath(a.out)
    r.use_file_extension = False
    return scene


def main(argv=None):
    a = parse_args(argv)
    import bpy  # noqa: E402
    import mathutils  # noqa: E402
    notes = []
    t0 = time.perf_counter()
    setup(bpy, mathutils, a, notes)
    load_s = time.perf_counter() - t0
    os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
    t1 = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    secs = time.perf_counter() - t1
    for n in notes:
        print(f"note: {n}", file=sys.stderr)
    sps = a.width * a.height * a.spp / secs
    name = os.path.splitext(os.path.basename(a.scene))[0]
    print(f"{name}: cycles {bpy.app.version_string} CPU {a.width}x{a.height} {a.spp} spp, bounces {a.max_depth - 1}: "
          f"{secs:.3f} s (render incl. sync), {sps / 1e6:.3f} M samples/s; wrote {a.out}", flush=True)
    if a.json:
        print(json.dumps({"scene": name, "file": a.scene, "width": a.width, "height": a.height, "spp": a.spp,
                          "max_depth": a.max_depth, "cycles_bounces": a.max_depth - 1, "seed": a.seed,
                          "seconds": secs, "seconds_load": load_s, "samples_per_s": sps, "out": a.out,
                          "filter_width": a.filter_width, "lighting_mode": a.lighting_mode,
                          "sampling_pattern": bpy.context.scene.cycles.sampling_pattern, "notes": notes,
                          "blender": bpy.app.version_string}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
