"""The native module boxmarch._core and the conversions of arguments in front of it, shared by
core.py and core_tools.py: a bad value becomes a one-line ValueError before any array reaches
the bindings."""
from __future__ import annotations

import numpy as np

try:
    from . import _core
except ImportError:  # installed as a Blender 4.2+ extension: the module comes from its platform wheel
    from boxmarch_native import _core  # noqa: F401 (used through this module's name)


def checked_int(value, name, lo=0, hi=2**31 - 1) -> int:
    """value as an int in [lo, hi], else a one-line ValueError (the bindings' own TypeError for
    an integer past 32 bits lists every overload)."""
    try:
        number = int(value)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} must be an integer, got {value!r}") from None
    if not lo <= number <= hi:
        raise ValueError(f"{name} must be in {lo}..{hi}, got {value!r}")
    return number


def checked_mask(values, name, length) -> np.ndarray:
    mask = np.ascontiguousarray(np.asarray(values) != 0, dtype=np.uint8)
    if mask.shape != (length,):
        raise ValueError(f"{name} must have shape ({length},), got {np.shape(values)}")
    return mask
