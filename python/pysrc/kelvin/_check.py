"""Checks of options at the Python boundary. PyO3's conversions raise OverflowError or TypeError
without the option's name (``spp=-1``, ``seed=2.5``); these raise a ValueError naming the option
and its value instead. Ranges come from the native module (``_kelvin.LIMITS``), so they are the
ones the Rust side enforces."""

from __future__ import annotations

import math
import numbers
from typing import Optional, Sequence, Tuple

import numpy as np

from . import _kelvin

# Floats cross as float32 unless said otherwise: past this they would become infinite.
F32_MAX = float(np.finfo(np.float32).max)


def _is_bool(value) -> bool:
    return isinstance(value, (bool, np.bool_))


def integer(name: str, value, limit: Optional[str] = None, lo: int = 0, hi: int = 2**32 - 1) -> int:
    """An integer option within ``LIMITS[limit]`` (or lo..=hi)."""
    if limit is not None:
        lo, hi = _kelvin.LIMITS[limit]
    if _is_bool(value) or not isinstance(value, numbers.Integral):
        raise ValueError(f"{name} = {value!r}: expected an integer in {lo}..={hi}")
    if not lo <= value <= hi:
        raise ValueError(f"{name} = {value!r} is outside {lo}..={hi}")
    return int(value)


def optional_integer(name: str, value, limit: Optional[str] = None, lo: int = 0, hi: int = 2**32 - 1):
    return None if value is None else integer(name, value, limit, lo, hi)


def real(name: str, value, lo: float = -F32_MAX, hi: float = F32_MAX, limit: Optional[str] = None) -> float:
    """A finite number within lo..hi (by default, any float32)."""
    if limit is not None:
        lo, hi = _kelvin.LIMITS[limit]
    if _is_bool(value) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name} = {value!r}: expected a number")
    if not math.isfinite(value):
        raise ValueError(f"{name} = {value!r}: not finite")
    if not lo <= value <= hi:
        raise ValueError(f"{name} = {value!r} is outside [{lo:g}, {hi:g}]")
    return float(value)


def optional_real(name: str, value, lo: float = -F32_MAX, hi: float = F32_MAX, limit: Optional[str] = None):
    return None if value is None else real(name, value, lo, hi, limit)


def vector(name: str, value, n: int = 3) -> Tuple[float, ...]:
    """``n`` finite float32 numbers (a position, a direction, a colour)."""
    try:
        items = tuple(value)
    except TypeError:
        raise ValueError(f"{name} = {value!r}: expected {n} numbers") from None
    if len(items) != n:
        raise ValueError(f"{name} = {value!r}: expected {n} numbers")
    for v in items:
        if _is_bool(v) or not isinstance(v, numbers.Real) or not math.isfinite(v) or abs(v) > F32_MAX:
            raise ValueError(f"{name} = {value!r}: expected {n} finite numbers")
    return tuple(float(v) for v in items)


def optional_vector(name: str, value, n: int = 3):
    return None if value is None else vector(name, value, n)


def integers(name: str, value, n: int, limit: str) -> Tuple[int, ...]:
    """``n`` integers each within ``LIMITS[limit]`` (a size, a crop)."""
    lo, hi = _kelvin.LIMITS[limit]
    try:
        items = tuple(value)
    except TypeError:
        raise ValueError(f"{name} = {value!r}: expected {n} integers in {lo}..={hi}") from None
    ok = len(items) == n and all(not _is_bool(v) and isinstance(v, numbers.Integral) and lo <= v <= hi
                                 for v in items)
    if not ok:
        raise ValueError(f"{name} = {value!r}: expected {n} integers in {lo}..={hi}")
    return tuple(int(v) for v in items)


def size(value: Sequence[int]) -> Tuple[int, int]:
    """An image's (width, height), each named as the Rust side names them."""
    lo, hi = _kelvin.LIMITS["size"]
    try:
        items = tuple(value)
    except TypeError:
        items = ()
    if len(items) != 2:
        raise ValueError(f"size = {value!r}: expected (width, height) in pixels")
    for side, v in zip(("width", "height"), items):
        if _is_bool(v) or not isinstance(v, numbers.Integral):
            raise ValueError(f"size = {value!r}: {side} = {v!r} is not an integer in {lo}..={hi}")
        if not lo <= v <= hi:
            raise ValueError(f"size = {value!r}: {side} = {v!r} is outside {lo}..={hi}")
    return int(items[0]), int(items[1])
