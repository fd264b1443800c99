"""Input checks shared by the library: each raises a ValueError (or TypeError) naming the argument."""

from __future__ import annotations

import numpy as np

__all__ = [
    "as_finite_array",
    "check_count",
    "check_nonnegative",
    "check_positive",
    "check_time_grid",
]


def as_finite_array(value: object, name: str, ndim: int | tuple[int, ...] | None = None) -> np.ndarray:
    """Return ``value`` as a float64 array, raising ``ValueError`` if it holds NaN/inf or has a wrong rank.

    Args:
        value: anything ``np.asarray`` accepts.
        name: the argument name used in the error message.
        ndim: the allowed number of dimensions (an int or a tuple of ints), or ``None`` for any.
    """
    try:
        array = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise TypeError(f"{name}: expected an array of numbers, got {type(value).__name__}") from error
    if ndim is not None:
        allowed = (ndim,) if isinstance(ndim, int) else tuple(ndim)
        if array.ndim not in allowed:
            raise ValueError(f"{name}: expected {' or '.join(map(str, allowed))} dimension(s), "
                             f"got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        bad = int(np.size(array) - np.count_nonzero(np.isfinite(array)))
        raise ValueError(f"{name}: contains {bad} NaN or infinite value(s)")
    return array


def check_nonnegative(value: float, name: str) -> float:
    """Return ``value`` as a float, raising ``ValueError`` unless it is a finite number >= 0."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name}: expected a number, got {type(value).__name__}")
    if not 0.0 <= float(value) < np.inf:
        raise ValueError(f"{name}: expected a finite number >= 0, got {value!r}")
    return float(value)


def check_positive(value: float, name: str) -> float:
    """Return ``value`` as a float, raising ``ValueError`` unless it is finite and > 0."""
    try:
        number = float(value)
    except (TypeError, ValueError) as error:
        raise TypeError(f"{name}: expected a number, got {type(value).__name__}") from error
    if not np.isfinite(number) or number <= 0.0:
        raise ValueError(f"{name}: expected a finite positive number, got {value!r}")
    return number


def check_time_grid(t: object, name: str = "t", *, uniform: bool = True, min_length: int = 2,
                    rtol: float = 1e-3) -> np.ndarray:
    """Validate a time vector ``t`` of shape ``[T]``: finite, strictly increasing and (optionally) evenly spaced.

    Returns the vector as float64. ``rtol`` is the allowed relative deviation of a step from the mean step.
    """
    t = as_finite_array(t, name, ndim=1)
    if t.size < min_length:
        raise ValueError(f"{name}: expected at least {min_length} time stamps, got {t.size}")
    steps = np.diff(t)
    if np.any(steps <= 0.0):
        first = int(np.argmax(steps <= 0.0))
        raise ValueError(f"{name}: time stamps must be strictly increasing "
                         f"(t[{first + 1}] = {t[first + 1]!r} <= t[{first}] = {t[first]!r})")
    if uniform and steps.size > 0:
        mean_step = (t[-1] - t[0]) / steps.size
        if np.max(np.abs(steps - mean_step)) > rtol * mean_step:
            raise ValueError(f"{name}: time stamps must be evenly spaced (steps range from "
                             f"{steps.min():.6g} to {steps.max():.6g}); resample them, e.g. "
                             "Demonstration.from_samples(t, Y, rate=...) or rdmp-gym fit --rate")
    return t


def check_count(value: object, name: str, low: int = 0) -> int:
    """Return ``value`` as an int, raising ``TypeError`` unless it is an integer (not a bool or a float)
    and ``ValueError`` unless it is ``>= low``."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name}: expected an integer, got {value!r}")
    if value < low:
        raise ValueError(f"{name}: expected an integer >= {low}, got {value!r}")
    return int(value)
