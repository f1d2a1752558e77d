"""kelvin.render against `kelvin render` (bit for bit), crops and threads, and bad input."""
import os
import signal
import subprocess
import threading

import numpy as np
import pytest

import kelvin

POINTS = "gltf/renderling/shadow_mapping_points.glb"


def cli_render(kelvin_bin, tmp_path, args):
    out = tmp_path / "cli.exr"
    run = subprocess.run([str(kelvin_bin), "render", *args, "-o", str(out)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    return kelvin.read_exr(out)


@pytest.mark.parametrize(
    "options, cli",
    [
        (dict(integrator="direct"), ["--integrator", "direct"]),
        (dict(max_depth=3, seed=5), ["--max-depth", "3", "--seed", "5"]),
        (dict(pattern="independent"), ["--pattern", "independent"]),
        (dict(color="spectral", light_sampler="power", mis=False), ["--color", "spectral", "--light-sampler", "power", "--no-mis"]),
        (dict(light_sampler="ris", candidates=4, integrator="direct"), ["--light-sampler", "ris", "--candidates", "4", "--integrator", "direct"]),
    ],
)
def test_render_equals_the_cli_bit_for_bit(data, kelvin_bin, tmp_path, options, cli):
    scene = data / POINTS
    image = kelvin.render(scene, size=(40, 30), spp=4, **options)
    assert image.shape == (30, 40, 3) and image.dtype == np.float32
    assert image.mean() > 0, "a lit image"
    expected = cli_render(kelvin_bin, tmp_path, [str(scene), "--size", "40x30", "--spp", "4", *cli])
    assert np.array_equal(image.view(np.uint32), expected.view(np.uint32))


def test_default_scene_with_an_environment_map_equals_the_cli(data, kelvin_bin, tmp_path):
    env = data / "env/spiaggia_di_mondello_1k.hdr"
    image = kelvin.render(size=(24, 16), spp=2, env=env, env_intensity=0.5, integrator="direct")
    expected = cli_render(kelvin_bin, tmp_path, ["--size", "24x16", "--spp", "2", "--env", str(env),
                                                 "--env-intensity", "0.5", "--integrator", "direct"])
    assert np.array_equal(image.view(np.uint32), expected.view(np.uint32))


def test_a_crop_is_its_region_of_the_full_render_at_any_thread_count(data):
    scene = data / POINTS
    full = kelvin.render(scene, size=(37, 23), spp=2, integrator="direct", threads=2)
    assert (full[3:19, 5:30] > 0).any(axis=2).sum() > 50, "the region is lit (93 of 400 pixels at 2 spp)"
    tile = kelvin.render(scene, size=(37, 23), spp=2, integrator="direct", threads=1, crop=(5, 3, 30, 19))
    assert np.array_equal(tile, full[3:19, 5:30])


def test_stats_and_warnings(data, tmp_path):
    stats = {}
    kelvin.render(data / POINTS, size=(8, 8), spp=1, stats=stats)
    assert stats["camera_samples"] == 64 and stats["spp"] == 1 and stats["seconds"] > 0
    # A node list naming a node the file lacks: a warning with its JSON pointer, and the rest renders.
    dangling = tmp_path / "dangling.gltf"
    dangling.write_text('{"asset": {"version": "2.0"}, "scenes": [{"nodes": [7]}]}')
    with pytest.warns(UserWarning, match=r"dangling.gltf: /scenes/0/nodes/0: node 7 does not exist"):
        image = kelvin.render(dangling, size=(8, 8), spp=1)
    assert image.shape == (8, 8, 3)


@pytest.mark.parametrize(
    "options, says",
    [
        (dict(spp=0), "spp = 0"),
        (dict(size=(0, 10)), "width = 0"),
        (dict(integrator="bidir"), "expected one of path, direct"),
        (dict(light_sampler="magic"), "light_sampler"),
        (dict(color="purple"), "color"),
        (dict(candidates=0), "candidates"),
        (dict(env_intensity=float("nan")), "env_intensity"),
        (dict(time=-1.0), "time"),
        (dict(environment_at=(0, float("nan"), 0)), "environment_at"),
        (dict(crop=(4, 4, 2, 2)), "empty"),
        (dict(crop=(0, 0, 4, 4), light_sampler="restir"), "ReSTIR"),
        (dict(sky="95,0,2024-06-21T10:00"), "latitude"),
        (dict(threads=0), "threads"),
        # Contradictions that used to be ignored silently.
        (dict(all_lights=True, light_sampler="restir"), "all_lights .* restir"),
        (dict(candidates=4), "candidates = 4 is for light_sampler = ris or restir, not bvh"),
        (dict(light_sampler="ris", neighbours=2), "neighbours = 2 is for light_sampler = restir, not ris"),
    ],
)
def test_bad_options_are_value_errors_naming_the_option(options, says):
    with pytest.raises(ValueError, match=says):
        kelvin.render(size=options.pop("size", (8, 8)), spp=options.pop("spp", 1), **options)


def test_missing_and_malformed_files_are_os_errors_naming_the_file(tmp_path, data):
    with pytest.raises(OSError, match="no-such-scene.glb"):
        kelvin.render(tmp_path / "no-such-scene.glb", size=(8, 8), spp=1)
    broken = tmp_path / "broken.gltf"
    broken.write_text('{"asset": {"version": "2.0"}, "scenes": [')
    with pytest.raises(OSError, match="broken.gltf"):
        kelvin.render(broken, size=(8, 8), spp=1)
    with pytest.raises(OSError, match="no-such-map.hdr"):
        kelvin.render(size=(8, 8), spp=1, env=tmp_path / "no-such-map.hdr")


def test_ctrl_c_stops_a_render():
    # Python's own SIGINT handler for the test: a process started in the background by a non-interactive shell
    # inherits SIGINT ignored, and Python then installs none (the test hung that way, started with `nohup ... &`).
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            kelvin.render(size=(512, 512), spp=4096)
    finally:
        timer.join()
        signal.signal(signal.SIGINT, previous)


def test_images_round_trip_and_bad_shapes_are_errors(tmp_path):
    rng = np.random.default_rng(1)
    image = rng.random((5, 7, 3), dtype=np.float32) * 100
    kelvin.write_exr(tmp_path / "a.exr", image)
    assert np.array_equal(kelvin.read_exr(tmp_path / "a.exr"), image)
    kelvin.write_png(tmp_path / "a.png", image)
    kelvin.write_png(tmp_path / "b.png", image.astype(np.float64), exposure=-2.0)
    assert (tmp_path / "a.png").stat().st_size > 0 and (tmp_path / "b.png").stat().st_size > 0
    with pytest.raises(ValueError, match="H x W x 3"):
        kelvin.write_exr(tmp_path / "c.exr", np.zeros((4, 4)))
    with pytest.raises(OSError, match="cannot read"):
        kelvin.read_exr(tmp_path / "missing.exr")
    with pytest.raises(OSError, match="cannot write"):
        kelvin.write_exr(tmp_path / "no-such-dir" / "d.exr", image)


def test_spectrum_and_ies_are_what_the_cli_prints(data, kelvin_bin):
    # Published values: D65's chromaticity (CIE 15:2004) and a blackbody's CCT is its temperature.
    d65 = kelvin.spectrum("illuminant:D65")
    assert abs(d65["xy"][0] - 0.3127) < 2e-4 and abs(d65["xy"][1] - 0.3290) < 2e-4
    assert abs(kelvin.spectrum("blackbody:2700")["cct_k"] - 2700) < 1
    with pytest.raises(ValueError, match="temperature"):
        kelvin.spectrum("blackbody:-5")
    path = data / "ies/luxcore/ASA_15M_R2.ies"
    summary = kelvin.ies(path)
    assert summary["stated_lumens"] == 13000 and summary["max_candela"] == 6019
    import json
    cli = subprocess.run([str(kelvin_bin), "ies", str(path), "--json"], capture_output=True, text=True, check=True)
    assert json.loads(cli.stdout) == summary
    with pytest.raises(OSError, match="no-such.ies"):
        kelvin.ies("no-such.ies")
