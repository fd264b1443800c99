"""Typed settings: the base of every learner's and agent's settings, their checks and their JSON form.

Settings are frozen dataclasses whose fields carry their types (lists of group names are tuples, per-group
factors are dicts); the command line derives its flags from them (:mod:`rdmp_gym.agents.cli`) and a run saves
them in ``config.json``. :meth:`Settings.from_dict` reads such a file back: an unknown name or a value of the
wrong type is an error naming the option; the comma strings that runs of earlier versions saved
(``"amplitude,approach"``, ``"approach=3"``) are read as the lists and dicts they meant. A name that is not a
setting but a value the settings fix (:meth:`Settings.fixed_values`) is read where it holds that value, and refused
with an error naming it where it holds another.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any, ClassVar, TypeVar, get_args, get_origin, get_type_hints

from typeguard import TypeCheckError, check_type

__all__ = ["Settings"]

S = TypeVar("S", bound="Settings")


def _legacy_items(text: str) -> tuple[str, ...]:
    """``"a, b"`` (a list as earlier versions saved it) -> ``("a", "b")``."""
    return tuple(item.strip() for item in text.split(",") if item.strip())


def _legacy_factors(text: str, name: str) -> dict[str, float]:
    """``"approach=3,amplitude=2"`` (per-group factors as earlier versions saved them) -> a dict."""
    factors = {}
    for item in _legacy_items(text):
        key, sep, value = item.partition("=")
        try:
            factors[key.strip()] = float(value) if sep else math.nan
        except ValueError:
            factors[key.strip()] = math.nan
        if not sep or not key.strip() or not math.isfinite(factors[key.strip()]):
            raise ValueError(f"{name}: {item!r} is not 'group=factor'")
    return factors


def _typed(value: Any, hint: Any, name: str) -> Any:
    """``value`` as the field type ``hint`` wants it (lists as tuples, ints as floats), checked by typeguard."""
    origin = get_origin(hint)
    if origin is tuple and isinstance(value, str):
        value = _legacy_items(value)
    elif origin is dict and isinstance(value, str):
        value = _legacy_factors(value, name)
    if origin is tuple and isinstance(value, list):
        value = tuple(value)
    if hint is float and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)
    if origin is dict and isinstance(value, Mapping) and get_args(hint)[1:] == (float,):
        value = {key: float(item) if isinstance(item, int) and not isinstance(item, bool) else item
                 for key, item in value.items()}
    if isinstance(value, bool) and hint in (int, float):
        raise TypeError(f"{name}: expected a number, got {value!r}")
    try:
        check_type(value, hint)
    except TypeCheckError as error:
        raise TypeError(f"{name}: expected {getattr(hint, '__name__', hint)}, got {value!r} ({error})") from None
    return value


def _same_value(value: Any, fixed: Any) -> bool:
    """Whether a saved ``value`` is the ``fixed`` one (a list or comma string for a tuple, an int for a float)."""
    if isinstance(fixed, tuple):
        value = _legacy_items(value) if isinstance(value, str) else tuple(value) if isinstance(value, list) else value
    if isinstance(fixed, bool) or isinstance(value, bool):
        return value is fixed
    same_kind = type(value) in (int, float) if isinstance(fixed, float) else type(value) is type(fixed)
    return same_kind and value == fixed


@dataclasses.dataclass(frozen=True)
class Settings:
    """Base of typed, validated settings that save as a JSON object (subclasses check values in ``__post_init__``)."""

    #: the name error messages use for the settings (e.g. the learner's name)
    label: ClassVar[str] = "settings"

    @classmethod
    def from_dict(cls: type[S], values: Mapping[str, Any] | None, what: str | None = None) -> S:
        """Build from a mapping (e.g. ``config.json``'s ``options``); unknown names and wrong types are errors.

        ``what`` names the settings in error messages (default: the class's ``label``).
        """
        what = what or cls.label
        values = dict(values or {})
        for name, fixed in cls.fixed_values().items():
            if name in values and not _same_value(value := values.pop(name), fixed):
                raise ValueError(f"{what}.{name}: not an option of {what}, which always runs with {name} = {fixed!r} "
                                 f"(got {value!r})")
        fields = {field.name for field in dataclasses.fields(cls)}
        unknown = sorted(set(values) - fields)
        if unknown:
            raise ValueError(f"{what}: unknown option(s) {unknown}; expected some of {sorted(fields)}")
        hints = get_type_hints(cls)
        return cls(**{name: _typed(value, hints[name], f"{what}.{name}") for name, value in values.items()})

    @classmethod
    def fixed_values(cls) -> dict[str, Any]:
        """``{name: value}``: names a saved ``config.json`` may hold that are not options here, with the value these
        settings always run with (:meth:`from_dict` reads such a name at that value and refuses another)."""
        return {}

    def to_dict(self) -> dict[str, Any]:
        """The fields as a JSON-friendly dict (tuples become lists)."""
        values = {field.name: getattr(self, field.name) for field in dataclasses.fields(self)}
        return {name: list(value) if isinstance(value, tuple) else dict(value) if isinstance(value, dict) else value
                for name, value in values.items()}

    def replace(self: S, **changes: Any) -> S:
        """A copy with ``changes`` (checked like :meth:`from_dict`)."""
        return type(self).from_dict({**self.to_dict(), **changes})
