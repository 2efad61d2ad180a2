"""The native module boxmarch._core and the conversions of arguments in front of it, shared by
core.py and core_tools.py: a bad value becomes a one-line ValueError before any array reaches
the bindings."""
from __future__ import annotations

import operator

import numpy as np

from . import NativeModuleMissing

WHEEL_PACKAGE = "boxmarch_native"  # the extension's platform wheel, which holds _core

try:
    from . import _core
except ImportError:  # installed as a Blender 4.2+ extension: the module comes from its platform wheel
    try:
        from boxmarch_native import _core  # noqa: F401 (used through this module's name)
    except ModuleNotFoundError as error:
        if error.name != WHEEL_PACKAGE:
            raise
        # A checkout on the path (PYTHONPATH=addon) before anything was built: say how to build.
        raise NativeModuleMissing(
            "boxmarch's native module (boxmarch/_core*.so) is not built: run `bash scripts/dev_build.sh` in the "
            "checkout (it builds into addon/boxmarch/), or use the Python `bash scripts/demo.sh` builds it into "
            "(.venv-demo/bin/python)", name=WHEEL_PACKAGE) from None


def checked_int(value, name, lo=0, hi=2**31 - 1) -> int:
    """value as an int in [lo, hi], else a one-line ValueError (the bindings' own TypeError for
    an integer past 32 bits lists every overload). Integers of any type and floats with an
    integral value are accepted; 2.7 is refused, not truncated to 2."""
    if isinstance(value, (float, np.floating)) and float(value).is_integer():
        value = int(value)
    try:
        number = operator.index(value)
    except TypeError:
        raise ValueError(f"{name} must be an integer, got {value!r}") from None
    if not lo <= number <= hi:
        raise ValueError(f"{name} must be in {lo}..{hi}, got {value!r}")
    return number


def checked_mask(values, name, length) -> np.ndarray:
    """Any array of booleans or numbers, one per element (nonzero: set), as the uint8 0/1 array
    the bindings take."""
    mask = np.ascontiguousarray(np.asarray(values) != 0, dtype=np.uint8)
    if mask.shape != (length,):
        raise ValueError(f"{name} must have shape ({length},), got {np.shape(values)}")
    return mask


def checked_indices(values, name, limit, lowest=0) -> np.ndarray:
    """Integer indices as a private int32 array, or a ValueError naming the first outside
    lowest..limit-1: NumPy would wrap a negative index silently and raise a bare IndexError past
    the end, and a cast to int32 would wrap 2**32 + 5 to 5 and truncate 2.7 to 2. The values are
    copied before they are checked, so another thread writing the caller's array cannot change
    them between the check and their use."""
    array = np.array(values)
    if array.dtype.kind not in "iub":
        raise ValueError(f"{name} must hold integers, got dtype {array.dtype}")
    flat = array.reshape(-1)
    bad = np.flatnonzero((flat < lowest) | (flat >= limit))
    if len(bad):
        raise ValueError(f"{name}[{int(bad[0])}] = {int(flat[bad[0]])} is outside {lowest}..{limit - 1}")
    return np.ascontiguousarray(array, np.int32)


def row_count(values) -> int:
    """Rows of an array-like (0 for a scalar or None), to size the checks of the arrays beside it
    before the bindings check the array itself."""
    return np.shape(values)[0] if np.ndim(values) else 0
