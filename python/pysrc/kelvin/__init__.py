"""kelvin: a physically based light system, from Python.

Renders of glTF scenes (``render``), the light system itself for many-light studies
(``LightSystem``), and the colorimetry and photometry of ``kelvin spectrum`` and ``kelvin ies``.
Images and point sets are NumPy arrays; values are photometric (cd/m^2 for radiance, lux for
irradiance) in linear sRGB. Work runs without the GIL; Ctrl-C stops a render.
"""

from __future__ import annotations

import json
import os
import warnings
from typing import Optional, Sequence, Tuple

import numpy as np

from . import _check, _kelvin

__all__ = ["render", "Scene", "write_exr", "write_png", "read_exr", "spectrum", "ies", "LightSystem", "luminance",
           "LUMINANCE_WEIGHTS"]


#: The Rec. 709 / sRGB luminance weights (the Y row of sRGB to XYZ), kelvin's own: linear sRGB . weights
#: is the photometric Y, so cd/m^2 of radiance and lux of irradiance.
LUMINANCE_WEIGHTS = np.array(_kelvin.LUMINANCE_WEIGHTS, dtype=np.float32)
LUMINANCE_WEIGHTS.flags.writeable = False


def luminance(rgb) -> np.ndarray:
    """The photometric Y of linear-sRGB values (... x 3, as any of kelvin's results): luminance in cd/m^2
    of an image, illuminance in lux of ``LightSystem.irradiance``. Not the mean of R, G and B, which for a
    coloured light is not a photometric quantity."""
    a = np.asarray(rgb, dtype=np.float32)
    if a.shape[-1:] != (3,):
        raise ValueError(f"rgb: expected ... x 3 values, got shape {a.shape}")
    return a @ LUMINANCE_WEIGHTS


def _path(p) -> Optional[str]:
    return None if p is None else os.fspath(p)


_RENDER_DOC = """Every keyword is the ``kelvin render`` option of the same name (``mis=False`` is ``--no-mis``);
    the same options give the same image, bit for bit. ``size`` is (width, height) in pixels, but the
    result is an H x W x 3 float32 array (rows first, as NumPy and matplotlib index images) of linear
    photometric radiance (cd/m^2, linear sRGB), rows top to bottom; with ``crop=(x0, y0, x1, y1)``
    (x before y, as ``size``) only that region of the full image, (y1 - y0) x (x1 - x0) x 3. Warnings are issued as ``UserWarning``s; pass a dict as
    ``stats`` to receive the render's counts and seconds.

    Raises ValueError for an option out of range, OSError for a file that does not load (the message
    names the file, and for glTF the JSON pointer) and KeyboardInterrupt when Ctrl-C stopped it. Every
    option is checked before it reaches the renderer: a negative, fractional, NaN or too large value is
    a ValueError naming the option and the value."""


def _warn(said) -> None:
    for w in said:
        warnings.warn(w, UserWarning, stacklevel=3)


class Scene:
    """A loaded scene that renders many times: a glTF file (or the embedded default scene) with an
    environment map and a sun and sky, loaded once. Between renders, ``pose`` moves what an
    animation moves, and the light system updates only that.

    ``Scene.load("scene.glb", sky="48.1,11.6,2026-06-21T12:00")`` loads; ``scene.render(spp=64)``
    renders; ``scene.lights``, ``scene.cameras`` and ``scene.animations`` describe the file.
    """

    def __init__(self, native, summary):
        self._native = native
        self.summary = summary

    @classmethod
    def load(cls, scene=None, *, env=None, env_intensity: float = 1.0, sky: Optional[str] = None,
             sky_intensity: float = 1.0) -> "Scene":
        """Load ``scene`` (a .gltf/.glb path; None: the embedded default scene) with an optional
        lat-long environment map (``env``, .exr or .hdr, ``env_intensity`` nit per texel value 1)
        and sun and sky (``sky`` = "LAT,LON,YYYY-MM-DDTHH:MM[,TURBIDITY]"). The loaders' warnings
        are issued as ``UserWarning``s; a file that does not load raises OSError naming the file
        and the JSON pointer, a bad sky ValueError."""
        env_intensity = _check.real("env_intensity", env_intensity, limit="intensity")
        sky_intensity = _check.real("sky_intensity", sky_intensity, limit="intensity")
        native, said = _kelvin.Scene.load(_path(scene), _path(env), env_intensity, sky, sky_intensity)
        _warn(said)
        return cls(native, native.summary())

    def render(
        self,
        *,
        size: Tuple[int, int] = (512, 512),
        spp: int = 32,
        time: Optional[float] = None,
        integrator: str = "path",
        max_depth: int = 16,
        roulette_depth: int = 3,
        light_sampler: str = "bvh",
        candidates: Optional[int] = None,
        neighbours: Optional[int] = None,
        radius: Optional[int] = None,
        biased_reuse: bool = False,
        color: str = "rgb",
        all_lights: bool = False,
        mis: bool = True,
        seed: int = 0,
        pattern: str = "sobol",
        threads: Optional[int] = None,
        environment_at: Optional[Sequence[float]] = None,
        crop: Optional[Tuple[int, int, int, int]] = None,
        stats: Optional[dict] = None,
    ) -> np.ndarray:
        """Render the scene in its current pose through its first camera (or, with
        ``environment_at=(x, y, z)``, as a lat-long map seen from that point).

        """
        c = _check
        pixels, width, height, said, info = self._native.render(
            c.size(size), c.integer("spp", spp, "spp"), c.optional_real("time", time, limit="time"), integrator,
            c.integer("max_depth", max_depth, "max_depth"), c.integer("roulette_depth", roulette_depth, "roulette_depth"),
            light_sampler, c.optional_integer("candidates", candidates, "candidates"),
            c.optional_integer("neighbours", neighbours, "neighbours"),
            c.optional_integer("radius", radius, "radius"), biased_reuse,
            color, all_lights, mis, c.integer("seed", seed, "seed"), pattern,
            c.optional_integer("threads", threads, "threads"), c.optional_vector("environment_at", environment_at),
            None if crop is None else c.integers("crop", crop, 4, "crop"))
        _warn(said)
        if stats is not None:
            stats.update(info)
        return pixels.reshape(height, width, 3)

    def pose(self, animation, t: float) -> dict:
        """Pose ``animation`` (its name or index) at ``t`` seconds, as ``kelvin render --frames`` poses
        frame ``t * fps``. Returns the counts of entities ``moved``, ``unchanged`` and ``frozen`` (meshes
        with a singular rest transform, which stay at rest: a UserWarning says so). Raises KeyError
        for an animation the scene lacks."""
        report = self._native.pose(animation, _check.real("t", t))
        if report["frozen"]:
            warnings.warn(f"{report['frozen']} animated meshes have a singular rest transform and stay at rest",
                          UserWarning, stacklevel=2)
        return report

    @property
    def lights(self) -> list:
        """The lights: the file's punctual lights (``kind`` point, spot, directional or ies; ``name``,
        ``node``, ``node_name``, ``color``, ``intensity`` in glTF units, ``range``, and ``position`` and
        ``direction`` in the current pose; spots add their cone half-angles in degrees), then the
        environment map (``kind`` environment) and the sun and sky (``kind`` sun_sky, given to ``load`` or
        carried by the file's ``KELVIN_sun_sky`` extension: ``direction`` toward the sun, ``turbidity``,
        ``intensity``, ``below_horizon``)."""
        return self._native.lights()

    @property
    def cameras(self) -> list:
        """The file's cameras (``name``, ``node``, ``yfov`` in degrees, ``aspect``, ``znear``, ``zfar``,
        and ``position`` and ``direction`` in the current pose); renders look through the first."""
        return self._native.cameras()

    @property
    def animations(self) -> list:
        """The file's animations: ``index``, ``name``, ``duration`` (s) and ``channels``."""
        return self._native.animations()


Scene.render.__doc__ += "    " + _RENDER_DOC


def render(
    scene=None,
    *,
    size: Tuple[int, int] = (512, 512),
    spp: int = 32,
    time: Optional[float] = None,
    env=None,
    env_intensity: float = 1.0,
    sky: Optional[str] = None,
    sky_intensity: float = 1.0,
    integrator: str = "path",
    max_depth: int = 16,
    roulette_depth: int = 3,
    light_sampler: str = "bvh",
    candidates: Optional[int] = None,
    neighbours: Optional[int] = None,
    radius: Optional[int] = None,
    biased_reuse: bool = False,
    color: str = "rgb",
    all_lights: bool = False,
    mis: bool = True,
    seed: int = 0,
    pattern: str = "sobol",
    threads: Optional[int] = None,
    environment_at: Optional[Sequence[float]] = None,
    crop: Optional[Tuple[int, int, int, int]] = None,
    stats: Optional[dict] = None,
) -> np.ndarray:
    """Render ``scene`` (a .gltf/.glb path; None: the embedded default scene) as ``kelvin render``
    does: ``Scene.load(scene, env=..., sky=...).render(...)`` in one call.

    """
    loaded = Scene.load(scene, env=env, env_intensity=env_intensity, sky=sky, sky_intensity=sky_intensity)
    return loaded.render(size=size, spp=spp, time=time, integrator=integrator, max_depth=max_depth,
                         roulette_depth=roulette_depth, light_sampler=light_sampler, candidates=candidates,
                         neighbours=neighbours, radius=radius, biased_reuse=biased_reuse, color=color,
                         all_lights=all_lights, mis=mis, seed=seed, pattern=pattern, threads=threads,
                         environment_at=environment_at, crop=crop, stats=stats)


render.__doc__ += "    " + _RENDER_DOC


def _image(image) -> Tuple[np.ndarray, int, int]:
    a = np.ascontiguousarray(image, dtype=np.float32)
    if a.ndim != 3 or a.shape[2] != 3 or a.shape[0] == 0 or a.shape[1] == 0:
        raise ValueError(f"image: expected an H x W x 3 array, got shape {a.shape}")
    return a.reshape(-1), a.shape[1], a.shape[0]


def write_exr(path, image) -> None:
    """Write an H x W x 3 linear image (rows first: a W x H image is shape (H, W, 3)) as a 32-bit
    float OpenEXR (ZIP compressed)."""
    flat, width, height = _image(image)
    _kelvin.write_exr(os.fspath(path), flat, width, height)


def write_png(path, image, exposure: Optional[float] = None) -> None:
    """Write an H x W x 3 linear image (rows first: a W x H image is shape (H, W, 3)) as a tone-mapped
    8-bit sRGB PNG; ``exposure`` in stops, automatic (the log-average luminance to 18% grey, as
    ``kelvin render``) when None."""
    flat, width, height = _image(image)
    _kelvin.write_png(os.fspath(path), flat, width, height, _check.optional_real("exposure", exposure))


def read_exr(path) -> np.ndarray:
    """Read an OpenEXR image's RGB as an H x W x 3 float32 array (rows first: a W x H image is
    shape (H, W, 3))."""
    flat, width, height = _kelvin.read_exr(os.fspath(path))
    return flat.reshape(height, width, 3)


def spectrum(spec: str) -> dict:
    """What ``kelvin spectrum SPEC --json`` prints: XYZ, xy, u'v', linear sRGB, CCT and Duv, luminous
    efficacy (and exitance and lambda_max for black and grey bodies). ``spec`` is ``blackbody:<K>``,
    ``graybody:<K>:<emissivity>``, ``illuminant:<name>``, ``daylight:<K>`` or a CSV file of nm,value rows."""
    return json.loads(_kelvin.spectrum_json(spec))


def ies(path) -> dict:
    """What ``kelvin ies FILE --json`` prints: header keywords, photometric type, stated and integrated
    lumens, peak candela, beam and field angles of an IES LM-63 file."""
    return json.loads(_kelvin.ies_json(os.fspath(path)))


def _columns(points, normals) -> Tuple[np.ndarray, np.ndarray, int]:
    p = np.ascontiguousarray(points, dtype=np.float32)
    n = np.ascontiguousarray(normals, dtype=np.float32)
    if p.ndim != 2 or p.shape[1] != 3:
        raise ValueError(f"points: expected an N x 3 array, got shape {p.shape}")
    if n.shape != p.shape:
        raise ValueError(f"normals: expected shape {p.shape} (one per point), got {n.shape}")
    return p.reshape(-1), n.reshape(-1), p.shape[0]


class LightSystem:
    """kelvin's light system on its own: lights and occluders added by id, and batches of surface
    points whose direct light (light choice, Sample_Li, shadow rays) comes back as NumPy arrays.

    ``sampler`` chooses one light per sample: ``"bvh"`` (the light BVH, default), ``"power"`` or
    ``"uniform"``; ``all_lights=True`` samples every light at every point instead. Amounts are
    photometric (candela, lumens, lux, nits) or radiometric where named (watts); ``color`` is linear
    sRGB with (1, 1, 1) the D65 white, ``temperature`` a blackbody in kelvin. Angles are degrees.
    Positions are metres, +Y up.

    ``color="rgb"`` (default) carries light as three linear-sRGB channels; ``color="spectral"`` as
    four wavelengths per sample (hero wavelengths, each sample its own), converted to linear sRGB
    through CIE XYZ. Both return the same quantities (lux and cd/m^2 in linear sRGB); spectral
    estimates add colour noise that falls with ``spp`` and over calls, and agree with RGB in the mean.

    Each ``irradiance`` or ``sample_li`` call draws the samples after the last call's (sample index
    i * spp + s of the ``seed``'s streams), so the mean of N calls converges as one call with N times
    the ``spp``; a new ``LightSystem`` with the same ``seed`` repeats the same sequence of results.
    """

    def __init__(self, sampler: str = "bvh", *, color: str = "rgb", seed: int = 0, all_lights: bool = False):
        self._native = _kelvin.LightSystem(sampler, color, _check.integer("seed", seed, "seed"), all_lights)

    def add_point(self, position, *, candela=None, lumens=None, watts=None, color=None, temperature=None,
                  radius: float = 0.0) -> int:
        """A point light (a sphere light of the same intensity when ``radius`` > 0). Returns its id."""
        c = _check
        return self._native.add_point(c.vector("position", position), c.optional_real("candela", candela),
                                      c.optional_real("lumens", lumens), c.optional_real("watts", watts),
                                      c.optional_vector("color", color), c.optional_real("temperature", temperature),
                                      c.real("radius", radius))

    def add_spot(self, position, direction, *, candela=None, lumens=None, inner_angle: float = 0.0,
                 outer_angle: float = 45.0, color=None, temperature=None) -> int:
        """A spot light pointing along ``direction``; full intensity within ``inner_angle`` of the axis,
        none beyond ``outer_angle`` (half-angles, degrees). Returns its id."""
        c = _check
        return self._native.add_spot(c.vector("position", position), c.vector("direction", direction),
                                     c.optional_real("candela", candela), c.optional_real("lumens", lumens),
                                     c.real("inner_angle", inner_angle), c.real("outer_angle", outer_angle),
                                     c.optional_vector("color", color), c.optional_real("temperature", temperature))

    def add_distant(self, direction, *, lux=None, color=None, temperature=None, angular_diameter: float = 0.0) -> int:
        """A distant light shining along ``direction`` (the sun: ``angular_diameter=0.53``). Returns its id."""
        c = _check
        return self._native.add_distant(c.vector("direction", direction), c.optional_real("lux", lux),
                                        c.optional_vector("color", color), c.optional_real("temperature", temperature),
                                        c.real("angular_diameter", angular_diameter))

    def add_area(self, center, normal, size, *, nits=None, lumens=None, color=None, temperature=None,
                 two_sided: bool = False) -> int:
        """A rectangular area light of ``size`` = (width, height) metres at ``center``, emitting along
        ``normal`` (both sides with ``two_sided``). Returns its id."""
        c = _check
        return self._native.add_area(c.vector("center", center), c.vector("normal", normal), c.vector("size", size, 2),
                                     c.optional_real("nits", nits), c.optional_real("lumens", lumens),
                                     c.optional_vector("color", color), c.optional_real("temperature", temperature),
                                     two_sided)

    def add_ies(self, path, position, direction=(0.0, -1.0, 0.0), *, lumens=None, multiplier: float = 1.0,
                color=None, temperature=None) -> int:
        """A luminaire with the IES LM-63 profile at ``path``, its photometric nadir along ``direction``;
        the file's candela times ``multiplier``, or scaled to ``lumens``. Returns its id."""
        c = _check
        return self._native.add_ies(os.fspath(path), c.vector("position", position), c.vector("direction", direction),
                                    c.optional_real("lumens", lumens), c.real("multiplier", multiplier),
                                    c.optional_vector("color", color), c.optional_real("temperature", temperature))

    def add_mesh(self, vertices, indices) -> int:
        """Occluding triangles in world space: ``vertices`` N x 3 (metres), ``indices`` M x 3. Returns its id."""
        v = np.ascontiguousarray(vertices, dtype=np.float32)
        i = np.asarray(indices)
        if v.ndim != 2 or v.shape[1] != 3:
            raise ValueError(f"vertices: expected an N x 3 array, got shape {v.shape}")
        if i.ndim != 2 or i.shape[1] != 3:
            raise ValueError(f"indices: expected an M x 3 array, got shape {i.shape}")
        if i.size and (not np.issubdtype(i.dtype, np.integer) or i.min() < 0 or i.max() >= v.shape[0]):
            raise ValueError(f"indices: expected integers in 0..{v.shape[0] - 1}")
        return self._native.add_mesh(v.reshape(-1), np.ascontiguousarray(i, dtype=np.uint32).reshape(-1))

    def load_gltf(self, path) -> None:
        """Add a glTF file's meshes, lights and cameras; the loader's warnings become UserWarnings."""
        for w in self._native.load_gltf(os.fspath(path)):
            warnings.warn(w, UserWarning, stacklevel=2)

    def move(self, id: int, position, direction=None) -> None:
        """Place light or mesh ``id`` at ``position`` (and turn it to ``direction``); the next run
        updates only what moved."""
        self._native.move_to(_check.integer("id", id, lo=0, hi=2**64 - 1), _check.vector("position", position),
                             _check.optional_vector("direction", direction))

    def remove(self, id: int) -> None:
        """Remove light or mesh ``id``."""
        self._native.remove(_check.integer("id", id, lo=0, hi=2**64 - 1))

    def irradiance(self, points, normals, *, spp: int = 64, threads: Optional[int] = None) -> np.ndarray:
        """Irradiance (lux, linear sRGB; N x 3 float32) at ``points`` (N x 3) facing ``normals``: an
        unbiased estimate from ``spp`` light samples per point, shadow rays included. Each call draws
        new samples (see the class docstring), so averaging calls converges."""
        p, n, count = _columns(points, normals)
        return self._native.irradiance(p, n, *self._run_options(spp, threads)).reshape(count, 3)

    def sample_li(self, points, normals, *, spp: int = 1, threads: Optional[int] = None) -> dict:
        """Every light sample of the points as columns: ``point`` (its point's index), ``radiance`` (E x 3,
        Li with visibility applied, cd/m^2 in linear sRGB), ``wi`` (E x 3, unit direction to the light),
        ``pdf`` (the density of the point's samples together: sum radiance * cos / pdf over a point's rows
        is its irradiance), ``occluded`` and ``delta`` (booleans). Each call draws new samples."""
        p, n, _ = _columns(points, normals)
        c = self._native.sample_li(p, n, *self._run_options(spp, threads))
        c["radiance"] = c["radiance"].reshape(-1, 3)
        c["wi"] = c["wi"].reshape(-1, 3)
        c["occluded"] = np.asarray(c["occluded"], dtype=bool)
        c["delta"] = np.asarray(c["delta"], dtype=bool)
        return c

    def warnings(self) -> list:
        """The last run's warnings (lights skipped and why)."""
        return self._native.warnings()

    @staticmethod
    def _run_options(spp, threads) -> Tuple[int, Optional[int]]:
        return _check.integer("spp", spp, "light_spp"), _check.optional_integer("threads", threads, "threads")
