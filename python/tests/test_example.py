"""examples/python/render_and_plot.py plots illuminance: the photometric Y of the irradiance, which
for point lights of known lumens has a closed form whatever their colour."""
import importlib.util
import math
import pathlib

import numpy as np

import kelvin

EXAMPLE = pathlib.Path(__file__).resolve().parents[2] / "examples/python/render_and_plot.py"


def test_luminance_of_a_warm_lights_irradiance_is_its_illuminance():
    # Y weights: (1, 1, 1) is D65 white of luminance 1; a 2700 K lamp's E_v = I / d^2 whatever its colour.
    assert math.isclose(float(kelvin.luminance(np.ones(3))), 1.0, rel_tol=1e-6)
    assert np.allclose(kelvin.LUMINANCE_WEIGHTS, [0.2126729, 0.7151522, 0.0721750])
    ls = kelvin.LightSystem()
    ls.add_point((0, 2, 0), candela=100.0, temperature=2700)
    e = ls.irradiance([[0, 0, 0], [0, 0, 0]], [[0, 1, 0], [0, 1, 0]], spp=1)
    assert e.shape == (2, 3) and np.allclose(kelvin.luminance(e), 25.0, rtol=1e-3), kelvin.luminance(e)
    assert abs(e.mean() - 25.0) > 0.02 * 25.0, "the mean of RGB is not illuminance for a coloured light"


def test_the_examples_exact_curve_is_the_illuminance_of_its_bulbs():
    spec = importlib.util.spec_from_file_location("render_and_plot", EXAMPLE)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)  # matplotlib is imported by main() only
    lights = example.bulbs(count=20, seed=3)
    xs = np.linspace(-10, 10, 41)
    exact, estimates = example.floor_illuminance(lights, xs, spps=(64,))
    # E_v = sum I h / d^3 with I = 800 lm / 4 pi sr for each isotropic bulb.
    expected = [sum(800 / (4 * math.pi) * p[1] / math.dist(p, (x, 0, 0)) ** 3 for p, _ in lights) for x in xs]
    assert np.allclose(exact, expected, rtol=1e-3), np.max(np.abs(exact / expected - 1))
    assert abs(estimates[64].mean() / np.mean(expected) - 1) < 0.05
