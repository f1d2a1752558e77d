#!/usr/bin/env python3
"""Writes tests/data/sunsky/mitsuba_sunsky_irradiance.csv: Mitsuba 3's `sunsky` emitter (scalar_spectral, the sun
on), integrated by quadrature into the daylight a scene receives, the reference of tests/lights_sunsky_reference.rs.

Per (turbidity, albedo, solar elevation) and per model wavelength (320, 360, ..., 720 nm), W/(m^2 nm):
  sky_h    irradiance of the sky alone (sun_scale 0) on a horizontal surface: integral of L cos(theta) over the
           upper hemisphere, in sun-centred coordinates (gamma = pi s^2 refines the circumsolar peak);
  sun_n    irradiance of the sun alone (sky_scale 0) on a surface facing it, Mitsuba's default sun
           (complex_sun false: the disc's radiance is its tabulated irradiance over the disc's solid angle);
  sun_n_ld the same with complex_sun true (Hosek-Wilkie 2013 radiance with limb darkening, each point of the disc
           at its own elevation), integrated over the disc.
Mitsuba's sky and sun are linear between the model wavelengths, so these 11 values carry the whole spectrum.
Mitsuba's up axis is +Z; the sun is put at azimuth 90 (toward +Y).

    python3 -m venv /work/mitsuba-venv && /work/mitsuba-venv/bin/pip install mitsuba==3.9.1 drjit==1.5.0 numpy
    /work/mitsuba-venv/bin/python bench/mitsuba/sunsky_reference.py [--check]

`--check` also integrates each row at half the resolution and prints the largest relative change (the quadrature's
own error bound).
"""

import argparse
import math
import sys
from pathlib import Path

import numpy as np

import mitsuba as mi

mi.set_variant("scalar_spectral")

WAVELENGTHS = [320.0 + 40.0 * i for i in range(11)]
# (turbidity, albedo, solar elevation in degrees)
ROWS = [
    (2.0, 0.3, 5.0),
    (3.0, 0.3, 10.0),
    (3.0, 0.3, 30.0),
    (3.0, 0.3, 60.0),
    (3.0, 0.0, 45.0),
    (3.0, 1.0, 20.0),
    (6.0, 0.3, 15.0),
    (6.0, 0.5, 75.0),
    (9.0, 0.2, 40.0),
]


def emitter(turbidity, albedo, elevation_deg, sun_scale, sky_scale, complex_sun=False):
    e = math.radians(elevation_deg)
    return mi.load_dict(
        {
            "type": "sunsky",
            "sun_direction": [0.0, math.cos(e), math.sin(e)],
            "turbidity": turbidity,
            "albedo": albedo,
            "sun_scale": sun_scale,
            "sky_scale": sky_scale,
            "complex_sun": complex_sun,
        }
    )


def radiance(em, d):
    """Spectral radiance toward unit direction d (into the scene it is -d), at the 11 model wavelengths."""
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(-d[0], -d[1], -d[2])
    out = []
    for k in range(0, 11, 4):
        wl = (WAVELENGTHS[k:k + 4] + [WAVELENGTHS[-1]] * 4)[:4]
        si.wavelengths = mi.Spectrum(wl)
        v = em.eval(si)
        out.extend([v[i] for i in range(4)][: min(4, 11 - k)])
    return np.array(out)


def frame(axis):
    a = np.asarray(axis, float)
    helper = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    t = np.cross(helper, a)
    t /= np.linalg.norm(t)
    return t, np.cross(a, t), a


def sky_horizontal(em, sun, n_gamma, n_psi):
    """Integral of L cos(theta) over the upper hemisphere, midpoint rule in (s, psi) with gamma = pi s^2."""
    t, b, a = frame(sun)
    total = np.zeros(11)
    for i in range(n_gamma):
        s = (i + 0.5) / n_gamma
        g = math.pi * s * s
        dg = 2.0 * math.pi * s / n_gamma
        for j in range(n_psi):
            p = 2.0 * math.pi * (j + 0.5) / n_psi
            d = math.sin(g) * (math.cos(p) * t + math.sin(p) * b) + math.cos(g) * a
            if d[2] <= 0.0:
                continue
            total += radiance(em, d) * d[2] * math.sin(g) * dg * (2.0 * math.pi / n_psi)
    return total


def sun_normal(em, sun, n_r, n_psi):
    """Integral of L over the sun's disc (Mitsuba's aperture, 0.5358 degrees), midpoint rule in (r^2, psi)."""
    half = math.radians(0.5 * 0.5358)
    t, b, a = frame(sun)
    omega = 2.0 * math.pi * (1.0 - math.cos(half))
    total = np.zeros(11)
    for i in range(n_r):
        # Uniform in solid angle: cos(gamma) uniform in [cos(half), 1].
        c = 1.0 - (i + 0.5) / n_r * (1.0 - math.cos(half))
        sg = math.sqrt(max(0.0, 1.0 - c * c))
        for j in range(n_psi):
            p = 2.0 * math.pi * (j + 0.5) / n_psi
            d = sg * (math.cos(p) * t + math.sin(p) * b) + c * a
            total += radiance(em, d) * omega / (n_r * n_psi)
    return total


def row(turbidity, albedo, elev, scale=1):
    e = math.radians(elev)
    sun = np.array([0.0, math.cos(e), math.sin(e)])
    sky = sky_horizontal(emitter(turbidity, albedo, elev, 0.0, 1.0), sun, 160 * scale, 192 * scale)
    plain = sun_normal(emitter(turbidity, albedo, elev, 1.0, 0.0), sun, 4 * scale, 8 * scale)
    limb = sun_normal(emitter(turbidity, albedo, elev, 1.0, 0.0, True), sun, 24 * scale, 24 * scale)
    return sky, plain, limb


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--check", action="store_true", help="also integrate at half resolution and print the change")
    ap.add_argument("--out", default=str(Path(__file__).resolve().parents[2] / "tests/data/sunsky/mitsuba_sunsky_irradiance.csv"))
    args = ap.parse_args()
    lines = [
        f"# Mitsuba {mi.__version__} sunsky (scalar_spectral), bench/mitsuba/sunsky_reference.py; W/(m^2 nm) at the model wavelengths",
        "turbidity,albedo,elevation_deg,quantity," + ",".join(f"{w:.0f}" for w in WAVELENGTHS),
    ]
    for t, a, elev in ROWS:
        full = row(t, a, elev, 2)
        if args.check:
            half = row(t, a, elev, 1)
            worst = max(float(np.max(np.abs(f - h) / np.maximum(np.abs(f), 1e-12))) for f, h in zip(full, half))
            print(f"T {t} albedo {a} elevation {elev}: half-resolution change {worst:.2e}", file=sys.stderr)
        for name, v in zip(["sky_h", "sun_n", "sun_n_ld"], full):
            lines.append(f"{t},{a},{elev},{name}," + ",".join(f"{x:.6e}" for x in v))
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
