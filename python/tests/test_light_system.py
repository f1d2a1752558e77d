"""kelvin.LightSystem: irradiance against closed forms for each light kind, moves and removals,
occluders, the sample columns' consistency, and bad input."""
import math
import pathlib

import numpy as np
import pytest

import kelvin

UP = np.array([[0.0, 1.0, 0.0]])


def floor(*points):
    p = np.array(points, dtype=np.float64)
    return p, np.repeat(UP, len(p), axis=0)


def test_point_light_inverse_square_cosine_law_move_and_remove():
    ls = kelvin.LightSystem()
    lamp = ls.add_point((0, 2, 0), candela=100.0)
    p, n = floor((0, 0, 0), (2, 0, 0))
    e = ls.irradiance(p, n, spp=1)
    # Delta light: E = I cos / d^2, white (D65) is equal RGB.
    expected = [100 / 4, 100 * (2 / math.sqrt(8)) / 8]
    assert np.allclose(e, np.array(expected)[:, None] * np.ones(3), rtol=2e-4)
    ls.move(lamp, (0, 4, 0))
    assert np.allclose(ls.irradiance(p[:1], n[:1], spp=1), 100 / 16, rtol=2e-4)
    ls.remove(lamp)
    assert np.all(ls.irradiance(p, n, spp=1) == 0)
    with pytest.raises(KeyError, match=str(lamp)):
        ls.remove(lamp)


def test_spot_and_distant_lights_closed_forms():
    ls = kelvin.LightSystem()
    ls.add_spot((0, 3, 0), (0, -1, 0), candela=900.0, inner_angle=10, outer_angle=20)
    p, n = floor((0, 0, 0), (0, 0, 3))  # on axis, and 45 degrees off (outside the cone)
    e = ls.irradiance(p, n, spp=1)
    assert np.allclose(e[0], 100.0, rtol=2e-4) and np.all(e[1] == 0)
    ls = kelvin.LightSystem()
    ls.add_distant((0, -1, -1), lux=1000.0)
    e = ls.irradiance(*floor((0, 0, 0)), spp=1)
    assert np.allclose(e, 1000 * math.cos(math.pi / 4), rtol=2e-4)


def rectangle_irradiance(radiance, width, height, distance):
    """Closed form at a point under the centre of a parallel rectangle: four corner rectangles,
    E = L/2 sum(X/sqrt(1+X^2) atan(Y/sqrt(1+X^2)) + Y/sqrt(1+Y^2) atan(X/sqrt(1+Y^2)))."""
    x, y = width / 2 / distance, height / 2 / distance
    one = x / math.sqrt(1 + x * x) * math.atan(y / math.sqrt(1 + x * x)) + y / math.sqrt(1 + y * y) * math.atan(
        x / math.sqrt(1 + y * y))
    return 4 * radiance / 2 * one


def test_area_light_monte_carlo_matches_the_closed_form_within_its_noise():
    ls = kelvin.LightSystem(seed=3)
    ls.add_area((0, 1, 0), (0, -1, 0), (2.0, 1.0), nits=1000.0)
    p, n = floor(*[(0, 0, 0)] * 64)
    e = ls.irradiance(p, n, spp=256)[:, 1]
    expected = rectangle_irradiance(1000.0, 2.0, 1.0, 1.0)
    error = e.std(ddof=1) / math.sqrt(len(e))
    assert abs(e.mean() - expected) < 4 * error + 1e-4 * expected, (e.mean(), expected, error)
    # Behind a one-sided light: nothing.
    assert np.all(ls.irradiance(np.array([[0, 2, 0]]), np.array([[0, -1, 0]]), spp=16) == 0)


def test_an_occluding_mesh_casts_a_shadow():
    ls = kelvin.LightSystem()
    ls.add_point((0, 2, 0), candela=100.0)
    ls.add_mesh([[-1, 1, -1], [1, 1, -1], [0, 1, 1]], [[0, 1, 2]])
    e = ls.irradiance(*floor((0, 0, 0), (5, 0, 0)), spp=1)
    assert np.all(e[0] == 0) and np.all(e[1] > 0)


def test_ies_luminaire_gives_the_files_nadir_candela(data):
    path = data / "ies/luxcore/ASA_15M_R2.ies"
    # Read the file's first candela value (C0, gamma 0) independently of kelvin's parser.
    lines = path.read_text(errors="replace").splitlines()
    tokens = " ".join(lines[next(i for i, l in enumerate(lines) if l.startswith("TILT")) + 1:]).split()
    multiplier, n_vertical, n_horizontal = float(tokens[2]), int(tokens[3]), int(tokens[4])
    nadir = float(tokens[13 + n_vertical + n_horizontal]) * multiplier
    ls = kelvin.LightSystem()
    ls.add_ies(path, (0, 3, 0), (0, -1, 0), multiplier=2.0)
    e = ls.irradiance(*floor((0, 0, 0)), spp=1)
    assert np.allclose(e, 2.0 * nadir / 9.0, rtol=1e-3), (e, nadir)


def test_sample_columns_sum_to_the_irradiance_and_blackbodies_are_warm():
    ls = kelvin.LightSystem(all_lights=True)
    ls.add_point((0, 2, 0), lumens=800.0, temperature=2700)
    ls.add_point((1, 3, 0), candela=50.0, color=(0.2, 0.4, 1.0))
    p, n = floor((0, 0, 0), (0.5, 0, 0.5))
    c = ls.sample_li(p, n)
    assert set(c) == {"point", "radiance", "wi", "pdf", "occluded", "delta"}
    assert len(c["point"]) == 4 and c["delta"].all() and not c["occluded"].any()
    cos = np.einsum("ij,ij->i", c["wi"], n[c["point"]])
    sums = np.zeros((2, 3))
    np.add.at(sums, c["point"], c["radiance"] * (cos / c["pdf"])[:, None])
    assert np.allclose(sums, ls.irradiance(p, n, spp=1), rtol=1e-5)
    warm = kelvin.LightSystem()
    warm.add_point((0, 2, 0), lumens=800.0, temperature=2700)
    r, g, b = warm.irradiance(*floor((0, 0, 0)), spp=1)[0]
    assert r > g > b > 0


def test_gltf_scene_lights_points(data):
    ls = kelvin.LightSystem()
    ls.load_gltf(data / "gltf/renderling/shadow_mapping_points.glb")
    e = ls.irradiance(*floor(*[(x, 0.01, 0) for x in np.linspace(-2, 2, 9)]), spp=16)
    assert np.isfinite(e).all() and e.sum() > 0


@pytest.mark.parametrize(
    "call, error, says",
    [
        (lambda ls: ls.add_point((0, float("nan"), 0)), ValueError, "position"),
        (lambda ls: ls.add_point((0, 1, 0), candela=-1.0), ValueError, "candela"),
        (lambda ls: ls.add_point((0, 1, 0), candela=1.0, lumens=2.0), ValueError, "one amount"),
        (lambda ls: ls.add_point((0, 1, 0), color=(1, 1, 1), temperature=3000), ValueError, "not both"),
        (lambda ls: ls.add_point((0, 1, 0), temperature=-5), ValueError, "temperature"),
        (lambda ls: ls.add_spot((0, 1, 0), (0, 0, 0)), ValueError, "zero vector"),
        (lambda ls: ls.add_spot((0, 1, 0), (0, -1, 0), inner_angle=30, outer_angle=20), ValueError, "angle"),
        (lambda ls: ls.add_area((0, 1, 0), (0, -1, 0), (0, 1)), ValueError, "size"),
        (lambda ls: ls.add_ies("no-such.ies", (0, 1, 0)), OSError, "no-such.ies"),
        (lambda ls: ls.add_mesh([[0, 0, 0]], [[0, 1, 2]]), ValueError, "indices"),
        (lambda ls: ls.load_gltf("no-such.glb"), OSError, "no-such.glb"),
        (lambda ls: ls.move(12345, (0, 0, 0)), KeyError, "12345"),
        (lambda ls: ls.irradiance([[0, 0, 0]], [[0, 1]]), ValueError, "normals"),
        (lambda ls: ls.irradiance([0, 0, 0], [0, 1, 0]), ValueError, "N x 3"),
        (lambda ls: ls.irradiance([[0, float("nan"), 0]], [[0, 1, 0]]), ValueError, "point 0"),
        (lambda ls: ls.irradiance([[0, 0, 0]], [[0, 0, 0]]), ValueError, "normal"),
        (lambda ls: ls.irradiance([["a", "b", "c"]], [[0, 1, 0]]), ValueError, "could not convert"),
        (lambda ls: ls.irradiance([[0, 0, 0]], [[0, 1, 0]], spp=0), ValueError, "spp"),
        (lambda ls: kelvin.LightSystem("magic"), ValueError, "sampler"),
    ],
)
def test_bad_input_is_a_python_exception_with_a_clear_message(call, error, says):
    ls = kelvin.LightSystem()
    ls.add_point((0, 2, 0))
    with pytest.raises(error, match=says):
        call(ls)
    # Nothing already added is lost.
    assert ls.irradiance(*floor((0, 0, 0)), spp=1).sum() > 0
