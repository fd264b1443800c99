"""State trees as files that never run code: a JSON document plus an ``.npz`` of its arrays.

A *state tree* is made of dicts (str keys), lists/tuples, ``None``, bools, ints, floats (NaN and inf
too), strings, numpy arrays of numbers or bools, ``numpy.random.Generator`` objects (their bit
generator's state) and ``bytes`` (opaque blobs, e.g. an SB3 model ``.zip``). :func:`encode` turns it
into a JSON-ready tree in which every array is a reference ``{"__array__": key}`` into a dict of
arrays, and every blob a reference ``{"__blob__": key}`` into a dict of byte strings; :func:`decode`
reverses it and checks every reference. Arrays are read with ``allow_pickle=False``: an object array
is refused, so reading never executes code. Tuples come back as lists.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["BIT_GENERATORS", "decode", "encode"]

#: bit generators a stored ``numpy.random.Generator`` may use (rebuilt by name, nothing else is called).
BIT_GENERATORS = {cls.__name__: cls for cls in (np.random.PCG64, np.random.PCG64DXSM, np.random.Philox,
                                                 np.random.SFC64, np.random.MT19937)}
_MARKERS = ("__array__", "__blob__", "__float__", "__generator__")


def encode(tree: Any, arrays: dict[str, np.ndarray], blobs: dict[str, bytes], path: str = "state") -> Any:
    """A JSON-ready copy of ``tree``; arrays go into ``arrays`` and byte strings into ``blobs``.

    Raises ``TypeError`` naming the path of a value that is none of the kinds above.
    """
    if tree is None or isinstance(tree, (bool, str)):
        return tree
    if isinstance(tree, (int, np.integer)):
        return int(tree)
    if isinstance(tree, (float, np.floating)):
        value = float(tree)
        return value if math.isfinite(value) else {"__float__": repr(value)}
    if isinstance(tree, np.bool_):
        return bool(tree)
    if isinstance(tree, np.ndarray):
        if tree.dtype.kind not in "biuf":
            raise TypeError(f"{path}: arrays must hold numbers or bools, got dtype {tree.dtype}")
        key = f"a{len(arrays)}"
        arrays[key] = np.ascontiguousarray(tree)
        return {"__array__": key}
    if isinstance(tree, (bytes, bytearray)):
        key = f"b{len(blobs)}"
        blobs[key] = bytes(tree)
        return {"__blob__": key}
    if isinstance(tree, np.random.Generator):
        name = type(tree.bit_generator).__name__
        if name not in BIT_GENERATORS:
            raise TypeError(f"{path}: bit generator {name} is not one of {sorted(BIT_GENERATORS)}")
        return {"__generator__": encode(tree.bit_generator.state, arrays, blobs, path)}
    if isinstance(tree, Mapping):
        out = {}
        for key, value in tree.items():
            if not isinstance(key, str):
                raise TypeError(f"{path}: keys must be strings, got {key!r}")
            if key in _MARKERS:
                raise TypeError(f"{path}: the key {key!r} is reserved")
            out[key] = encode(value, arrays, blobs, f"{path}.{key}")
        return out
    if isinstance(tree, (list, tuple)):
        return [encode(value, arrays, blobs, f"{path}[{i}]") for i, value in enumerate(tree)]
    raise TypeError(f"{path}: cannot store a {type(tree).__name__} (expected numbers, strings, lists, dicts, "
                    "arrays, numpy Generators or bytes)")


def decode(tree: Any, arrays: Mapping[str, np.ndarray], blobs: Mapping[str, bytes], path: str = "state") -> Any:
    """Rebuild what :func:`encode` wrote; a broken reference or marker is a ``ValueError`` naming its path."""
    if tree is None or isinstance(tree, (bool, int, float, str)):
        return tree
    if isinstance(tree, list):
        return [decode(value, arrays, blobs, f"{path}[{i}]") for i, value in enumerate(tree)]
    if not isinstance(tree, dict):
        raise ValueError(f"{path}: unexpected {type(tree).__name__}")
    marker = [key for key in _MARKERS if key in tree]
    if not marker:
        return {key: decode(value, arrays, blobs, f"{path}.{key}") for key, value in tree.items()}
    if len(tree) != 1:
        raise ValueError(f"{path}: a {marker[0]} reference must be the only key, got {sorted(tree)}")
    key, value = marker[0], tree[marker[0]]
    if key == "__float__":
        if value not in ("nan", "inf", "-inf"):
            raise ValueError(f"{path}: expected 'nan', 'inf' or '-inf', got {value!r}")
        return float(value)
    if key == "__generator__":
        state = decode(value, arrays, blobs, path)
        name = state.get("bit_generator") if isinstance(state, dict) else None
        if name not in BIT_GENERATORS:
            raise ValueError(f"{path}: unknown bit generator {name!r}")
        generator = np.random.Generator(BIT_GENERATORS[name]())
        try:
            generator.bit_generator.state = state
        except (TypeError, ValueError, KeyError) as error:
            raise ValueError(f"{path}: not a valid {name} state ({error})") from error
        return generator
    store = arrays if key == "__array__" else blobs
    if not isinstance(value, str) or value not in store:
        raise ValueError(f"{path}: refers to {value!r}, which the {'arrays' if store is arrays else 'blobs'} "
                         "do not hold")
    return store[value].copy() if key == "__array__" else store[value]
