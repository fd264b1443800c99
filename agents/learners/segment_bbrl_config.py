"""``bbrl_segments``' settings, apart from its module so that declaring and checking them does not import torch."""

from __future__ import annotations

from dataclasses import dataclass

from rdmp_gym.validation import check_choice, check_range

from ..registry import register
from .bbrl_config import BBRLConfig

__all__ = ["SCALES", "SegmentBBRLConfig"]

SCALES = ("dimension", "common")


@dataclass(frozen=True)
class SegmentBBRLConfig(BBRLConfig):
    """Settings of :class:`~rdmp_gym.agents.learners.segment_bbrl.SegmentBBRL` (beyond :class:`BBRLConfig`).

    Attributes:
        segments: equal parts of the episode's control steps that the cost is split into and credited per part
            (the critic's outputs).
        episode_share: share of each dimension's credit that comes from the whole episode's advantage rather than
            from the segments in which the dimension acts (0: only the segments; 1: the episode, as bbrl without
            per-step credit). Costs the task books at the end (e.g. the wiping task's coverage, judged once) reach
            the dimensions that act early through it.
        scale: how advantages become weights: ``"dimension"`` (PI²'s min-max per dimension: every dimension's best
            sample gets the full eliteness ``h``) or ``"common"`` (one scale, the range of the episode advantages,
            for every dimension: a dimension whose segments hardly differ between samples stays nearly where it is).
        baseline: ``"network"`` (default): the critic ``V(s)`` of every segment's cost, fitted to the ``history``
            batches before the ones it judges (off-policy: those samples came from earlier policies); ``"ridge"``:
            a ridge regression on the context alone.
        history: batches the critic is fitted to.
        value_epochs: Adam steps of the critic per update.
        credit: ``"step"`` (default): per-segment credit; ``"episode"``: one advantage per episode (the ablation).
    """

    segments: int = 16
    episode_share: float = 0.25
    scale: str = "dimension"
    baseline: str = "network"
    history: int = 50
    value_epochs: int = 100

    def __post_init__(self) -> None:
        super().__post_init__()
        check_range(self.segments, "segments", 1, None)
        check_range(self.episode_share, "episode_share", 0.0, 1.0)
        check_choice(self.scale, "scale", SCALES)


register("bbrl_segments", SegmentBBRLConfig, "rdmp_gym.agents.learners.segment_bbrl:SegmentBBRL", uses_context=True)
