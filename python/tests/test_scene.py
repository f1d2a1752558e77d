"""kelvin.Scene: a scene loaded once, described, posed and rendered many times; against
`kelvin render --frames` bit for bit, and against the closed form of its animation."""
import json
import subprocess

import numpy as np
import pytest

import kelvin

LAMP = "gltf/kelvin/animated_lamp.gltf"  # scripts/make_test_gltf.py documents its channels
POINTS = "gltf/renderling/shadow_mapping_points.glb"


def bits(image):
    return image.view(np.uint32)


def test_the_animated_lamp_describes_its_light_camera_and_animation(data):
    scene = kelvin.Scene.load(data / LAMP)
    assert "1 lights, 1 cameras, 1 animations" in scene.summary
    [lamp] = scene.lights
    assert (lamp["kind"], lamp["name"], lamp["node_name"], lamp["intensity"]) == ("point", "lamp", "lamp", 10.0)
    np.testing.assert_allclose(lamp["position"], (0.0, 1.0, 0.0), atol=1e-6)
    [camera] = scene.cameras
    assert camera["yfov"] == pytest.approx(np.degrees(0.01))
    np.testing.assert_allclose(camera["position"], (0.0, 3.0, 3.0), atol=1e-6)
    # The camera looks 45 degrees down towards the floor.
    np.testing.assert_allclose(camera["direction"], (0.0, -np.sqrt(0.5), -np.sqrt(0.5)), atol=1e-6)
    [day] = scene.animations
    assert (day["index"], day["name"], day["channels"]) == (0, "day", 5)
    assert day["duration"] > 0


@pytest.mark.parametrize("t", [0.5, 1.5, 2.5])
def test_posing_moves_the_lamp_to_the_closed_form_of_its_keyframes(data, t):
    scene = kelvin.Scene.load(data / LAMP)
    report = scene.pose("day", t)
    assert report["moved"] > 0 and report["frozen"] == 0
    # The rig steps to x = 0.6 at t = 1 and scales along a cubic spline (zero tangents) from 1 to 2
    # over two seconds, while the lamp rises linearly from 1 to 2 in the rig's space.
    u = min(t / 2.0, 1.0)
    rig_x = 0.0 if t < 1.0 else 0.6
    rig_scale = 1.0 + 3.0 * u * u - 2.0 * u**3
    np.testing.assert_allclose(scene.lights[0]["position"], (rig_x, rig_scale * (1.0 + u), 0.0), atol=1e-5)
    # Posing by index is the same animation.
    assert scene.pose(0, t)["moved"] == 0, "posing the same time again moves nothing"


def test_posed_renders_equal_kelvin_render_frames_bit_for_bit(data, kelvin_bin, tmp_path):
    fps = 4.0
    run = subprocess.run([str(kelvin_bin), "render", str(data / LAMP), "--frames", "0..3", "--fps", str(fps),
                          "--size", "24x16", "--spp", "2", "--integrator", "direct", "-o",
                          str(tmp_path / "frame_##.exr")], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    scene = kelvin.Scene.load(data / LAMP)
    means = []
    for frame in range(4):
        scene.pose("day", frame / fps)
        image = scene.render(size=(24, 16), spp=2, integrator="direct")
        expected = kelvin.read_exr(tmp_path / f"frame_{frame:02}.exr")
        assert np.array_equal(bits(image), bits(expected)), f"frame {frame}"
        means.append(image.mean())
    assert len(set(means)) == 4, "every frame differs: the lamp moves"


def test_one_scene_under_changing_settings_renders_as_the_cli_does(data, kelvin_bin, tmp_path):
    """The hard case: the settings of one render (sampler kind, colour mode, seed, integrator) must
    not leak into the next render of the same loaded scene; each equals `kelvin render`'s own load."""
    scene = kelvin.Scene.load(data / POINTS)
    runs = [
        (dict(light_sampler="power", color="spectral", seed=3), ["--light-sampler", "power", "--color", "spectral",
                                                                 "--seed", "3"]),
        (dict(light_sampler="bvh", integrator="direct"), ["--integrator", "direct"]),
        (dict(light_sampler="ris", candidates=4, integrator="direct", mis=False),
         ["--light-sampler", "ris", "--candidates", "4", "--integrator", "direct", "--no-mis"]),
        (dict(light_sampler="uniform", all_lights=True, max_depth=2),
         ["--light-sampler", "uniform", "--all-lights", "--max-depth", "2"]),
        (dict(light_sampler="bvh", integrator="direct"), ["--integrator", "direct"]),
    ]
    for options, cli in runs:
        again = scene.render(size=(20, 14), spp=2, **options)
        out = tmp_path / "cli.exr"
        run = subprocess.run([str(kelvin_bin), "render", str(data / POINTS), "--size", "20x14", "--spp", "2", *cli,
                              "-o", str(out)], capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        assert again.mean() > 0
        assert np.array_equal(bits(again), bits(kelvin.read_exr(out))), options


def test_environment_and_sky_are_listed_with_the_file_lights(data):
    scene = kelvin.Scene.load(env=data / "env/spiaggia_di_mondello_1k.hdr", env_intensity=2.0,
                              sky="48.1,11.6,2024-06-21T10:00", sky_intensity=0.5)
    kinds = [(light["kind"], light["intensity"]) for light in scene.lights]
    assert kinds[-2:] == [("environment", 2.0), ("sun_sky", 0.5)]
    assert scene.animations == [] and scene.summary is None
    assert scene.lights[-1]["direction"][1] > 0 and not scene.lights[-1]["below_horizon"]


def test_a_sky_in_the_scene_file_is_listed_and_renders_as_the_same_sky_given_to_load(data, tmp_path):
    doc = json.loads((data / LAMP).read_text())
    del doc["nodes"][3]["extensions"], doc["extensions"]  # the lamp
    doc["extensions"] = {"KELVIN_sun_sky": {"latitude": 48.1, "longitude": 11.6, "time": "2024-06-21T22:00"}}
    path = tmp_path / "night.gltf"
    path.write_text(json.dumps(doc))
    with pytest.warns(UserWarning, match="degrees below the horizon at 48.1, 11.6"):
        scene = kelvin.Scene.load(path)
    [sky] = scene.lights
    assert sky["kind"] == "sun_sky" and sky["below_horizon"]
    doc["extensions"]["KELVIN_sun_sky"]["time"] = "2024-06-21T10:00"
    path.write_text(json.dumps(doc))
    by_file = kelvin.render(path, size=(12, 8), spp=2, integrator="direct")
    del doc["extensions"]
    path.write_text(json.dumps(doc))
    by_option = kelvin.render(path, size=(12, 8), spp=2, integrator="direct", sky="48.1,11.6,2024-06-21T10:00")
    assert by_file.mean() > 0 and np.array_equal(bits(by_file), bits(by_option))


def test_bad_poses_are_errors_that_say_what_exists(data):
    scene = kelvin.Scene.load(data / LAMP)
    with pytest.raises(KeyError, match=r"animation night: not in the scene \(it has 0: day\)"):
        scene.pose("night", 0.0)
    with pytest.raises(KeyError, match="animation 1: not in the scene"):
        scene.pose(1, 0.0)
    with pytest.raises(ValueError, match=r"(?i)t = nan"):
        scene.pose("day", float("nan"))
    still = kelvin.Scene.load(data / POINTS)
    with pytest.raises(KeyError, match="has no animation"):
        still.pose(0, 0.0)
    with pytest.raises(ValueError, match="spp = 0"):
        still.render(size=(8, 8), spp=0)
    # A failed call changes nothing: the scene still renders.
    assert still.render(size=(8, 8), spp=1, integrator="direct").shape == (8, 8, 3)


def test_load_errors_name_the_file_and_the_sky(tmp_path):
    with pytest.raises(OSError, match="no-such-scene.glb"):
        kelvin.Scene.load(tmp_path / "no-such-scene.glb")
    with pytest.raises(ValueError, match="latitude"):
        kelvin.Scene.load(sky="95,0,2024-06-21T10:00")


@pytest.mark.parametrize("mirror", [(-1.0, 1.0, 1.0), (1.0, -1.0, 1.0), (1.0, 1.0, -1.0), (-2.0, 0.5, 1.0)])
def test_cameras_under_a_mirrored_parent_look_along_the_world_matrix(data, tmp_path, mirror):
    """glTF, Bevy and three.js aim a camera along its world matrix applied to -Z; a parent scaled by
    a mirror (as Blender writes one) must not turn it round."""
    doc = json.loads((data / LAMP).read_text())
    doc["nodes"].append({"name": "mirror", "scale": list(mirror), "children": [4]})
    doc["scenes"][0]["nodes"] = [0, 1, 2, len(doc["nodes"]) - 1]
    path = tmp_path / "mirrored.gltf"
    path.write_text(json.dumps(doc))
    [camera] = kelvin.Scene.load(path).cameras
    # The child looks 45 degrees down towards -Z; the parent's matrix is diag(mirror).
    want = np.array(mirror) * np.array([0.0, -np.sqrt(0.5), -np.sqrt(0.5)])
    np.testing.assert_allclose(camera["direction"], want / np.linalg.norm(want), atol=1e-6)
    np.testing.assert_allclose(camera["position"], np.array(mirror) * np.array([0.0, 3.0, 3.0]), atol=1e-5)
