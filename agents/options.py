"""Validated option dataclasses: a misspelt or ill-typed option is an error that names it."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any, TypeVar, get_type_hints

__all__ = ["check_choice", "check_range", "from_options", "to_options"]

T = TypeVar("T")


def from_options(cls: type[T], options: Mapping[str, Any] | None, what: str) -> T:
    """Build the dataclass ``cls`` from ``options``; unknown names are a ``ValueError`` naming them.

    Values are checked against the field's annotation (``bool``, ``int``, ``float``, ``str``, tuples);
    an int is accepted for a float field. ``what`` names the option set in error messages.
    """
    options = dict(options or {})
    fields = {field.name: field for field in dataclasses.fields(cls)}
    unknown = sorted(set(options) - set(fields))
    if unknown:
        raise ValueError(f"{what}: unknown option(s) {unknown}; expected some of {sorted(fields)}")
    hints = get_type_hints(cls)
    values = {}
    for name, value in options.items():
        values[name] = _coerce(value, hints[name], f"{what}.{name}")
    return cls(**values)


def to_options(config: Any) -> dict[str, Any]:
    """The fields of a dataclass ``config`` as a JSON-friendly dict (tuples become lists)."""
    return {key: list(value) if isinstance(value, tuple) else value
            for key, value in dataclasses.asdict(config).items()}


def _coerce(value: Any, hint: Any, name: str) -> Any:
    if hint is bool:
        if not isinstance(value, bool):
            raise TypeError(f"{name}: expected true or false, got {value!r}")
        return value
    if hint is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise TypeError(f"{name}: expected an integer, got {value!r}")
        return value
    if hint is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise TypeError(f"{name}: expected a number, got {value!r}")
        return float(value)
    if hint is str:
        if not isinstance(value, str):
            raise TypeError(f"{name}: expected a string, got {value!r}")
        return value
    return value


def check_range(value: float, name: str, low: float | None = None, high: float | None = None, *,
                low_open: bool = False, high_open: bool = False) -> None:
    """Raise ``ValueError`` naming ``name`` unless ``low (<|<=) value (<|<=) high``."""
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
