"""Input checks shared by the library, the envs and the agents (their one home): each raises a ValueError (or a
TypeError) naming the argument or setting."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np

__all__ = [
    "SettingTypeError",
    "as_finite_array",
    "check_choice",
    "check_count",
    "check_flag",
    "check_integer",
    "check_mapping",
    "check_nonnegative",
    "check_number",
    "check_optional_number",
    "check_pair",
    "check_path",
    "check_positive",
    "check_range",
    "check_time_grid",
    "is_number",
    "refuse_settings",
]


class SettingTypeError(TypeError, ValueError):
    """A setting of the wrong type. It is a ``TypeError`` and also a ``ValueError``, so code that catches the
    ``ValueError`` the env raised for bad settings before they were data still sees it."""


def is_number(value: object) -> bool:
    """Whether ``value`` is a real number (an int or float of Python or numpy; not a bool)."""
    return not isinstance(value, (bool, np.bool_)) and isinstance(value, (int, float, np.integer, np.floating))


def check_number(value: object, name: str, *, low: float | None = None, high: float | None = None,
                 strict_low: bool = True, what: str = "") -> float:
    """``value`` as a finite float, checked against ``low`` (strictly above unless ``strict_low``) and ``high``;
    ``what`` describes it in the message (e.g. ``" (N)"``)."""
    if not is_number(value):
        raise SettingTypeError(f"{name}: expected a number{what}, got {value!r} ({type(value).__name__})")
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"{name}: expected a finite number{what}, got {value!r}")
    if low is not None and (number <= low if strict_low else number < low):
        raise ValueError(f"{name}: expected a number {'>' if strict_low else '>='} {low:g}{what}, got {value!r}")
    if high is not None and number > high:
        raise ValueError(f"{name}: expected a number <= {high:g}{what}, got {value!r}")
    return number


def check_optional_number(value: object, name: str, **kwargs: object) -> float | None:
    """None, or :func:`check_number` of ``value``."""
    return None if value is None else check_number(value, name, **kwargs)  # type: ignore[arg-type]


def check_integer(value: object, name: str, low: int = 1) -> int:
    """``value`` as an int, ``>= low``; an integral float (as JSON writes numbers) is accepted, a bool is not (see
    :func:`check_count` for a check that takes integers only)."""
    if is_number(value) and float(value).is_integer():  # type: ignore[arg-type]
        number = int(value)  # type: ignore[call-overload]
        if number < low:
            raise ValueError(f"{name}: expected an integer >= {low}, got {value!r}")
        return number
    raise SettingTypeError(f"{name}: expected an integer, got {value!r} ({type(value).__name__})")


def check_flag(value: object, name: str) -> bool:
    """``value`` as a bool (True or False, of Python or numpy)."""
    if not isinstance(value, (bool, np.bool_)):
        raise SettingTypeError(f"{name}: expected True or False, got {value!r} ({type(value).__name__})")
    return bool(value)


def check_pair(value: object, name: str, what: str) -> tuple[float, float]:
    """``value`` as two finite numbers (a sequence of two); ``what`` says what the pair is."""
    if isinstance(value, (str, bytes, Mapping)) or not isinstance(value, Iterable):
        raise SettingTypeError(f"{name}: expected {what}, got {value!r}")
    items = tuple(value)
    if len(items) != 2:
        raise ValueError(f"{name}: expected {what}, got {value!r}")
    return tuple(check_number(item, name, what=f" ({what})") for item in items)  # type: ignore[return-value]


def check_path(value: object, name: str) -> str | None:
    """None, or ``value`` (a non-empty str or Path) as a str."""
    if value is None:
        return None
    if not isinstance(value, (str, Path)) or not str(value):
        raise SettingTypeError(f"{name}: expected a file path, got {value!r} ({type(value).__name__})")
    return str(value)


def check_mapping(value: object, name: str, what: str) -> dict:
    """``value`` as a dict with str keys; ``what`` says what it maps."""
    if not isinstance(value, Mapping):
        raise SettingTypeError(f"{name}: expected {what}, got {value!r} ({type(value).__name__})")
    for key in value:
        if not isinstance(key, str):
            raise SettingTypeError(f"{name}: expected names (str) as keys, got {key!r}")
    return dict(value)


def check_range(value: float, name: str, low: float | None = None, high: float | None = None, *,
                low_open: bool = False, high_open: bool = False) -> None:
    """Raise ``ValueError`` naming ``name`` unless ``low (<|<=) value (<|<=) high`` (NaN is out of range)."""
    too_low = low is not None and (value <= low if low_open else value < low)
    too_high = high is not None and (value >= high if high_open else value > high)
    if too_low or too_high or value != value:
        left = "(" if low_open else "["
        right = ")" if high_open else "]"
        raise ValueError(f"{name}: expected a value in {left}{low}, {high}{right}, got {value!r}")


def check_choice(value: str, name: str, choices: tuple[str, ...]) -> None:
    """Raise ``ValueError`` naming ``name`` unless ``value`` is one of ``choices``."""
    if value not in choices:
        raise ValueError(f"{name}: expected one of {list(choices)}, got {value!r}")


def refuse_settings(refused: Mapping[str, str], settings: Mapping[str, object], env: str) -> None:
    """Raise ``ValueError`` naming the first of the ``refused`` settings (name -> why ``env`` cannot honour it) that
    ``settings`` give a value other than None or False."""
    for name, why in refused.items():
        if settings.get(name) not in (None, False):
            raise ValueError(f"{name}: {env} cannot honour it ({why})")


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
