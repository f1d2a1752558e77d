"""The Python error contract: every numeric option given a negative, a fractional, a NaN or a huge
value raises a ValueError naming the option and the value (never PyO3's OverflowError or TypeError);
and the package ships its type stubs."""
import ast
import inspect
import pathlib

import numpy as np
import pytest

import kelvin

NAN, HUGE_INT, HUGE = float("nan"), 10**30, 1e300
P, N = [[0, 0, 0]], [[0, 1, 0]]
IES = pathlib.Path(__file__).resolve().parents[2] / "tests/data/ies/luxcore/ASA_15M_R2.ies"


def lit():
    ls = kelvin.LightSystem()
    ls.add_point((0, 2, 0))
    return ls


# (option, call with the value, values that must be refused). Integer options refuse fractions;
# options where a negative is meaningful (positions, exposure) only refuse non-finite or huge values.
INTEGER_OPTIONS = [
    ("spp", lambda v: kelvin.render(size=(8, 8), spp=v)),
    ("seed", lambda v: kelvin.render(size=(8, 8), spp=1, seed=v)),
    ("threads", lambda v: kelvin.render(size=(8, 8), spp=1, threads=v)),
    ("max_depth", lambda v: kelvin.render(size=(8, 8), spp=1, max_depth=v)),
    ("roulette_depth", lambda v: kelvin.render(size=(8, 8), spp=1, roulette_depth=v)),
    ("candidates", lambda v: kelvin.render(size=(8, 8), spp=1, candidates=v)),
    ("neighbours", lambda v: kelvin.render(size=(8, 8), spp=1, neighbours=v)),
    ("radius", lambda v: kelvin.render(size=(8, 8), spp=1, radius=v)),
    ("size", lambda v: kelvin.render(size=(8, v), spp=1)),
    ("crop", lambda v: kelvin.render(size=(8, 8), spp=1, crop=(v, 0, 4, 4))),
    ("seed", lambda v: kelvin.LightSystem(seed=v)),
    ("spp", lambda v: lit().irradiance(P, N, spp=v)),
    ("spp", lambda v: lit().sample_li(P, N, spp=v)),
    ("threads", lambda v: lit().irradiance(P, N, threads=v)),
    ("threads", lambda v: lit().sample_li(P, N, threads=v)),
    ("id", lambda v: lit().move(v, (0, 1, 0))),
]
FLOAT_OPTIONS = [
    ("time", lambda v: kelvin.render(size=(8, 8), spp=1, time=v), True),
    ("env_intensity", lambda v: kelvin.Scene.load(env_intensity=v), True),
    ("sky_intensity", lambda v: kelvin.Scene.load(sky_intensity=v), True),
    ("environment_at", lambda v: kelvin.render(size=(8, 8), spp=1, environment_at=(0, v, 0)), False),
    ("candela", lambda v: lit().add_point((0, 1, 0), candela=v), True),
    ("lumens", lambda v: lit().add_point((0, 1, 0), lumens=v), True),
    ("watts", lambda v: lit().add_point((0, 1, 0), watts=v), True),
    ("radius", lambda v: lit().add_point((0, 1, 0), radius=v), True),
    ("temperature", lambda v: lit().add_point((0, 1, 0), temperature=v), True),
    ("color", lambda v: lit().add_point((0, 1, 0), color=(1, v, 1)), True),
    ("position", lambda v: lit().add_point((0, v, 0)), False),
    ("inner_angle", lambda v: lit().add_spot((0, 1, 0), (0, -1, 0), inner_angle=v), True),
    ("outer_angle", lambda v: lit().add_spot((0, 1, 0), (0, -1, 0), outer_angle=v), True),
    ("lux", lambda v: lit().add_distant((0, -1, 0), lux=v), True),
    ("angular_diameter", lambda v: lit().add_distant((0, -1, 0), angular_diameter=v), True),
    ("size", lambda v: lit().add_area((0, 1, 0), (0, -1, 0), (1.0, v)), True),
    ("nits", lambda v: lit().add_area((0, 1, 0), (0, -1, 0), (1.0, 1.0), nits=v), True),
    ("multiplier", lambda v: lit().add_ies(IES, (0, 1, 0), multiplier=v), True),
    ("exposure", lambda v: kelvin.write_png("/no-such-dir/never.png", np.ones((2, 2, 3)), exposure=v), False),
]
CASES = [pytest.param(name, call, v, id=f"{name}-{v!r}"[:40])
         for name, call in INTEGER_OPTIONS for v in (-1, 2.5, NAN, HUGE_INT)]
CASES += [pytest.param(name, call, v, id=f"{name}-{v!r}")
          for name, call, negative_is_bad in FLOAT_OPTIONS for v in ([-1.0] if negative_is_bad else []) + [NAN, HUGE]]


@pytest.mark.parametrize("name, call, value", CASES)
def test_a_bad_number_is_a_value_error_naming_the_option_and_the_value(name, call, value):
    with pytest.raises(ValueError) as raised:
        call(value)
    said = str(raised.value)
    assert name in said, said
    shown = {-1: ["-1"], 2.5: ["2.5"], HUGE_INT: [str(HUGE_INT)], HUGE: ["1e+300"]}.get(value, ["nan", "NaN"])
    assert any(s in said for s in shown), said


def test_size_is_width_then_height_and_arrays_are_rows_first():
    assert kelvin.render(size=(12, 5), spp=1, integrator="direct").shape == (5, 12, 3)
    for f in (kelvin.render, kelvin.Scene.render, kelvin.write_exr, kelvin.write_png, kelvin.read_exr):
        assert "H x W x 3" in f.__doc__ and "(width, height)" in f.__doc__ or "(H, W, 3)" in f.__doc__, f


def test_the_package_ships_stubs_that_match_the_api():
    package = pathlib.Path(kelvin.__file__).parent
    assert (package / "py.typed").exists() and (package / "_kelvin.pyi").exists()
    stub = ast.parse((package / "__init__.pyi").read_text())
    defs = {n.name: n for n in stub.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    constants = {n.target.id for n in stub.body if isinstance(n, ast.AnnAssign)}
    for name in kelvin.__all__:
        obj = getattr(kelvin, name)
        if not callable(obj):
            assert name in constants, f"{name}: not in __init__.pyi"
            continue
        assert name in defs, f"{name}: not in __init__.pyi"
        pairs = [(obj, defs[name])] if inspect.isfunction(obj) else [
            (getattr(obj, m.name), m) for m in defs[name].body if isinstance(m, ast.FunctionDef)]
        if inspect.isclass(obj):
            public = {m for m, _ in inspect.getmembers(obj) if not m.startswith("_")}
            stubbed = {m.name for m in defs[name].body if isinstance(m, ast.FunctionDef)}
            assert public - {"summary"} <= stubbed, (name, public - stubbed)
        for runtime, stubbed in pairs:
            if isinstance(runtime, property):
                continue
            a = stubbed.args
            stub_params = [p.arg for p in a.posonlyargs + a.args + a.kwonlyargs]
            params = list(inspect.signature(runtime).parameters)
            if stub_params[:1] in (["self"], ["cls"]) and params[:1] not in (["self"], ["cls"]):
                stub_params = stub_params[1:]
            assert stub_params == params, (name, runtime, stub_params, params)
