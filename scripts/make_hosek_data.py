#!/usr/bin/env python3
"""Writes src/light/infinite/sunsky/data/hosek_wilkie.bin, the Hosek-Wilkie sky and sun tables
kelvin's sun-and-sky light evaluates (see the README next to it), from the repackaging of the
same tables that Mitsuba 3 ships (pip package `mitsuba`, file mitsuba/data/sunsky/sunsky_datasets.bin,
a tensor file of float64 fields). Stdlib only.

    python3 scripts/make_hosek_data.py /path/to/mitsuba/data/sunsky/sunsky_datasets.bin

The output is headerless little-endian float32, the fields one after another in this order and
shape (C order): sky_params_rgb [10 turbidity, 2 albedo, 6 control points, 3 channels, 9 params],
sky_rad_rgb [10, 2, 6, 3], sky_params_spec [10, 2, 6, 11 wavelengths, 9], sky_rad_spec [10, 2, 6, 11],
sun_rad_spec [10 turbidity, 45 elevation pieces, 11 wavelengths, 4 polynomial coefficients,
constant term first], sun_ld_spec [11 wavelengths, 6 limb-darkening coefficients].
The script checks a few values against the authors' headers (ArHosekSkyModelData_Spectral.h and
ArHosekSkyModelData_RGB.h, version 1.4a) before writing.
"""
import struct
import sys
from pathlib import Path

FIELDS = [  # name, shape
    ("sky_params_rgb", [10, 2, 6, 3, 9]),
    ("sky_rad_rgb", [10, 2, 6, 3]),
    ("sky_params_spec", [10, 2, 6, 11, 9]),
    ("sky_rad_spec", [10, 2, 6, 11]),
    ("sun_rad_spec", [10, 45, 11, 4]),
    ("sun_ld_spec", [11, 6]),
]
# Offsets of the float64 fields in Mitsuba 3.9's sunsky_datasets.bin (its TensorFile header).
OFFSETS = {
    "sun_rad_spec": 427, "sun_ld_spec": 418027, "sky_rad_rgb": 418555, "sky_params_rgb": 421435,
    "sky_rad_spec": 447355, "sky_params_spec": 457915,
}
# (field, flat index, value in the authors' headers)
CHECKS = [
    ("sky_params_spec", 0, -1.341049e1),  # dataset320, albedo 0, turbidity 1, first value
    ("sky_params_spec", 11 * 9, -1.426825e1),  # dataset320, second control point
    ("sky_params_spec", 2 * 6 * 11 * 9, -1.298333e1),  # dataset320, albedo 0, turbidity 2
    ("sky_params_rgb", 0, -1.099459),  # datasetRGB1[0]
    ("sun_ld_spec", 0, 0.087657),  # limbDarkeningDataset320[0]
]


def main(src):
    raw = Path(src).read_bytes()
    out = bytearray()
    fields = {}
    for name, shape in FIELDS:
        n = 1
        for s in shape:
            n *= s
        vals = struct.unpack_from("<%dd" % n, raw, OFFSETS[name])
        fields[name] = vals
        out += struct.pack("<%df" % n, *vals)
    for name, i, want in CHECKS:
        got = fields[name][i]
        assert abs(got - want) <= 1e-6 * abs(want), (name, i, got, want)
    dst = Path(__file__).resolve().parent.parent / "src/light/infinite/sunsky/data/hosek_wilkie.bin"
    dst.write_bytes(out)
    print(f"wrote {dst} ({len(out)} bytes)")


if __name__ == "__main__":
    main(sys.argv[1])
