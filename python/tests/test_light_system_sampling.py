"""kelvin.LightSystem's sampling: spectral mode against RGB, and calls that draw new samples, so
that the mean of N calls converges as 1/sqrt(N)."""
import math

import numpy as np
import pytest

import kelvin

from test_light_system import floor, rectangle_irradiance


def per_point_irradiance(ls, p, n, method, spp):
    """One call's irradiance estimate per point, from `irradiance` or summed from `sample_li`'s columns."""
    if method == "irradiance":
        return ls.irradiance(p, n, spp=spp)
    c = ls.sample_li(p, n, spp=spp)
    cos = np.maximum(np.einsum("ij,ij->i", c["wi"], n[c["point"]]), 0)
    e = np.zeros((len(p), 3))
    np.add.at(e, c["point"], c["radiance"] * (cos / c["pdf"])[:, None])
    return e


@pytest.mark.parametrize("method", ["irradiance", "sample_li"])
def test_spectral_irradiance_of_a_blackbody_is_the_rgb_one_in_the_mean(method):
    # A point light is a delta light: RGB mode gives the exact irradiance; spectral mode's only noise
    # is its wavelengths', which averages out over points (each its own wavelengths).
    rgb = kelvin.LightSystem()
    rgb.add_point((0, 2, 0), candela=100.0, temperature=2700)
    p, n = floor(*[(0, 0, 0)] * 512)
    exact = rgb.irradiance(p[:1], n[:1], spp=1)[0]
    spectral = kelvin.LightSystem(color="spectral", seed=5)
    spectral.add_point((0, 2, 0), candela=100.0, temperature=2700)
    e = per_point_irradiance(spectral, p, n, method, spp=2)
    assert np.isfinite(e).all() and e.std(axis=0).min() > 0, "spectral estimates vary with their wavelengths"
    error = e.std(axis=0, ddof=1) / math.sqrt(len(e))
    assert np.all(np.abs(e.mean(axis=0) - exact) < 4 * error + 2e-3 * exact), (e.mean(axis=0), exact, error)


def test_spectral_and_rgb_agree_under_a_partly_shadowed_area_light():
    means, errors = [], []
    for color in ("rgb", "spectral"):
        ls = kelvin.LightSystem(color=color, seed=2)
        ls.add_area((0, 1, 0), (0, -1, 0), (2.0, 1.0), nits=1000.0, temperature=4000)
        ls.add_mesh([[-5, 0.5, -5], [-5, 0.5, 5], [0.25, 0.5, 0]], [[0, 1, 2]])  # hides part of the light
        p, n = floor(*[(0, 0, 0)] * 256)
        e = np.mean([ls.irradiance(p, n, spp=4) for _ in range(8)], axis=0)
        means.append(e.mean(axis=0))
        errors.append(e.std(axis=0, ddof=1) / math.sqrt(len(e)))
    (rgb, spectral), error = means, np.hypot(*errors)
    unshadowed = rectangle_irradiance(1000.0, 2.0, 1.0, 1.0)
    assert 0.1 * unshadowed < rgb.mean() < 0.9 * unshadowed, "partly shadowed"
    assert np.all(np.abs(spectral - rgb) < 4 * error), (rgb, spectral, error)


@pytest.mark.parametrize("method", ["irradiance", "sample_li"])
def test_calls_draw_new_samples_so_the_mean_of_calls_converges(method):
    # Under a rectangle light (closed form), the error of the mean of 64 calls is at most a quarter
    # of the mean of 4 calls' (1/sqrt(N); stratified samples may do better), measured over 256 points.
    ls = kelvin.LightSystem(seed=11)
    ls.add_area((0, 1, 0), (0, -1, 0), (2.0, 1.0), nits=1000.0)
    p, n = floor(*[(0, 0, 0)] * 256)
    expected = rectangle_irradiance(1000.0, 2.0, 1.0, 1.0)
    calls = np.array([per_point_irradiance(ls, p, n, method, spp=1)[:, 1] for _ in range(64)])
    assert not np.array_equal(calls[0], calls[1]), "a second call draws other samples"
    rms = {k: math.sqrt(np.mean((calls[:k].mean(axis=0) - expected) ** 2)) for k in (1, 4, 64)}
    assert rms[4] < rms[1] / 1.6 and rms[64] < rms[4] / 3.2, rms
    # The calls' mean is unbiased: within 4 standard errors of the closed form.
    assert abs(calls.mean() - expected) < 4 * calls.mean(axis=0).std(ddof=1) / math.sqrt(256), (calls.mean(), expected)


def test_the_same_seed_repeats_the_same_sequence_of_calls():
    runs = []
    for _ in range(2):
        ls = kelvin.LightSystem(seed=4)
        ls.add_area((0, 1, 0), (0, -1, 0), (2.0, 1.0), nits=1000.0)
        runs.append([ls.irradiance(*floor((0, 0, 0), (0.3, 0, 0)), spp=2) for _ in range(3)])
    assert all(np.array_equal(a, b) for a, b in zip(*runs))
    assert not np.array_equal(runs[0][0], runs[0][1])
