"""Render a glTF file with kelvin and plot it with matplotlib, next to a light-system study.

    pip install ./python matplotlib
    python examples/python/render_and_plot.py [SCENE.glb] [-o plot.png]

The left panel is the path-traced image (tone-mapped for display); the right one the illuminance
(lux: the photometric Y, ``kelvin.luminance`` of the linear-sRGB irradiance) on a line of floor points
under 100 random point lights, estimated with the light BVH at 1, 4 and 64 samples per point against
every light summed exactly.
"""
import argparse
import pathlib

import numpy as np

import kelvin

REPO = pathlib.Path(__file__).resolve().parents[2]


def tone_map(image, exposure=None):
    y = kelvin.luminance(image)
    if exposure is None:
        lit = y[y > 0]
        exposure = np.log2(0.18 / np.exp(np.log(lit).mean())) if lit.size else 0.0
    v = np.clip(image * 2.0 ** exposure, 0, None)
    srgb = np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.power(v, 1 / 2.4) - 0.055)
    return np.clip(srgb, 0, 1)


def bulbs(count=100, seed=7):
    """`count` 800 lm bulbs of random colour temperature, 1-4 m over a 20 x 20 m floor: (position, kelvin)."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        x, z = rng.uniform(-10, 10, size=2)
        out.append(((x, rng.uniform(1, 4), z), rng.uniform(2200, 6500)))
    return out


def add_lights(system, lights):
    for position, temperature in lights:
        system.add_point(position, lumens=800.0, temperature=temperature)
    return system


def floor_illuminance(lights, xs, spps=(1, 4, 64)):
    """Illuminance (lx) at floor points (x, 0, 0) facing up: every light summed exactly, and the
    light BVH's estimate at each of `spps` samples per point."""
    points = np.stack([xs, np.zeros_like(xs), np.zeros_like(xs)], axis=1)
    normals = np.tile([0.0, 1.0, 0.0], (len(xs), 1))
    # Point lights are delta lights: one sample of every light is the exact irradiance.
    exact = kelvin.luminance(add_lights(kelvin.LightSystem(all_lights=True), lights).irradiance(points, normals, spp=1))
    system = add_lights(kelvin.LightSystem(), lights)
    return exact, {spp: kelvin.luminance(system.irradiance(points, normals, spp=spp)) for spp in spps}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("scene", nargs="?", default=REPO / "tests/data/gltf/bevy/CornellBox.glb")
    parser.add_argument("-o", "--output", default="kelvin_plot.png")
    args = parser.parse_args()

    stats = {}
    image = kelvin.render(args.scene, size=(256, 256), spp=16, stats=stats)
    print(f"rendered {args.scene} in {stats['seconds']:.2f} s, {stats['camera_samples'] / stats['seconds'] / 1e6:.2f} M samples/s")

    xs = np.linspace(-10, 10, 200)
    exact, estimates = floor_illuminance(bulbs(), xs)

    # Imported here: the tests import this module for floor_illuminance without matplotlib.
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.5))
    left.imshow(tone_map(image))
    left.set_axis_off()
    left.set_title(pathlib.Path(args.scene).name)
    right.plot(xs, exact, "k", label="every light")
    for spp, estimate in estimates.items():
        right.plot(xs, estimate, lw=0.8, label=f"light BVH, {spp} spp")
    right.set_xlabel("x (m)")
    right.set_ylabel("illuminance (lx, photometric Y)")
    right.legend()
    fig.tight_layout()
    fig.savefig(args.output, dpi=100)
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
