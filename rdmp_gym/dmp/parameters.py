"""Named, selectable groups of a flat parameter vector (what a learner sees of a DMP).

Groups, in this order: ``periodic`` (``[d, N]`` weights), ``transient:k`` (``[d, M_k]`` weights of
transient k), ``initial:k`` (``(phi0, r0)`` of transient k), ``anchor`` (``[d]``) and ``amplitude``
(``[d]`` factors that scale the movement about the anchor, 1 = as demonstrated), for a DMP whose anchor
travels, ``sweep`` (``[K, d]`` via points of the anchor's path, :mod:`rdmp_gym.dmp.sweep`), and, for a DMP that
encodes the end of the movement, ``stop`` (``[d, S]`` stop weights, :mod:`rdmp_gym.dmp.stopping`). The short
names ``transient`` and ``initial`` select every transient's group.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import NamedTuple

__all__ = ["GROUPS", "GroupKey", "ParameterLayout", "group_key"]

GROUPS = ("periodic", "transient", "initial", "anchor", "amplitude", "sweep", "stop")

#: the groups that come once per transient (named ``"kind:k"``)
PER_TRANSIENT = ("transient", "initial")


class GroupKey(NamedTuple):
    """A parameter group's name taken apart: its ``kind`` (one of :data:`GROUPS`) and, for the groups of one
    transient (``transient:k``, ``initial:k``), the transient's index (``None`` otherwise)."""

    kind: str
    transient: int | None = None

    def __str__(self) -> str:
        return self.kind if self.transient is None else f"{self.kind}:{self.transient}"


def group_key(name: str) -> GroupKey:
    """The :class:`GroupKey` of a full group name (``"periodic"``, ``"transient:0"``, ``"initial:2"``, ...)."""
    kind, _, index = name.partition(":")
    if kind not in GROUPS or (kind in PER_TRANSIENT) != bool(index) or (index and not index.isdigit()):
        raise ValueError(f"groups: {name!r} is not a full parameter group name")
    return GroupKey(kind, int(index) if index else None)


class ParameterLayout:
    """Sizes of every parameter group of one DMP; resolves group selections to slices.

    Args:
        n_dims: degrees of freedom d.
        n_periodic: periodic basis functions N.
        transient_sizes: transient basis functions per transient ``(M_1, ..., M_K)``.
        stop_size: number of stop weights ``d * S`` (0: no ``stop`` group).
        sweep_size: number of via-point coordinates ``K * d`` of the anchor's path (0: no ``sweep`` group).
    """

    def __init__(self, n_dims: int, n_periodic: int, transient_sizes: Sequence[int], stop_size: int = 0,
                 sweep_size: int = 0) -> None:
        self.sizes: dict[str, int] = {"periodic": n_dims * n_periodic}
        self.sizes.update({str(GroupKey("transient", k)): n_dims * m for k, m in enumerate(transient_sizes)})
        self.sizes.update({str(GroupKey("initial", k)): 2 for k in range(len(transient_sizes))})
        self.sizes["anchor"] = n_dims
        self.sizes["amplitude"] = n_dims
        if sweep_size:
            self.sizes["sweep"] = int(sweep_size)
        if stop_size:
            self.sizes["stop"] = int(stop_size)
        self.n_transients = len(transient_sizes)

    def resolve(self, groups: str | Iterable[str] | None) -> list[str]:
        """Expand a selection (``None`` = all groups) into full group names in canonical order."""
        if groups is None:
            return list(self.sizes)
        requested = [groups] if isinstance(groups, str) else list(groups)
        chosen: set[str] = set()
        for name in requested:
            if name in self.sizes:
                chosen.add(name)
            elif name in PER_TRANSIENT:
                chosen.update(str(GroupKey(name, k)) for k in range(self.n_transients))
            else:
                raise ValueError(f"groups: unknown parameter group {name!r}; expected one of "
                                 f"{list(GROUPS)} or one of {list(self.sizes)}")
        if not chosen:
            raise ValueError("groups: select at least one parameter group")
        return [name for name in self.sizes if name in chosen]

    def keys(self, groups: str | Iterable[str] | None = None) -> list[GroupKey]:
        """The selected groups as :class:`GroupKey` s, in canonical order."""
        return [group_key(name) for name in self.resolve(groups)]

    def slices(self, groups: str | Iterable[str] | None = None) -> dict[str, slice]:
        """Slices of each selected group inside the vector made of just the selected groups."""
        out, start = {}, 0
        for name in self.resolve(groups):
            out[name] = slice(start, start + self.sizes[name])
            start += self.sizes[name]
        return out

    def size(self, groups: str | Iterable[str] | None = None) -> int:
        """Length of the vector made of the selected groups."""
        return sum(self.sizes[name] for name in self.resolve(groups))
