"""Contextual episodic policy search: a linear-Gaussian upper-level policy over DMP parameters.

Policy: ``u = W x(s) + ε``, ``x(s) = [1, φ(s)]`` with standardised context features ``φ(s) [F]`` (the
observation minus its centre, over its scale; a *gated* feature, such as the cup's position, which is
only defined when its indicator, the cup's presence, is 1, is standardised over the contexts where it
is defined and is 0 where it is not), ``W = [θ̄, K]`` ``[n, F + 1]``; the executed action is
``squash(u)`` in ``(-1, 1)`` (:func:`~rdmp_gym.agents.learners.smooth_exploration.squash`, monotone; nothing is
clipped).
``ε`` is smooth per weight block (:class:`~rdmp_gym.agents.learners.smooth_exploration.SmoothNoise`) with one
standard deviation per block. Each update keeps the last ``reuse`` batches and weights their samples:

* ``reps``: contextual REPS (Kupcsik et al. 2013; Deisenroth, Neumann, Peters 2013, sec. 2.4.2):
  ``d_k ∝ exp((R_k - V(s_k)) / η)`` with ``V(s) = vᵀφ(s)`` and ``η``, ``v`` from the dual
  ``g = η ε + mean_k vᵀφ_k + η log mean_k exp((R_k - vᵀφ_k) / η)`` (KL bound ``ε``);
* ``pibb``: PI^BB's ``exp(-h (A - min A) / (max A - min A))`` on the advantage ``A_k = J_k - b(s_k)``
  over a ridge-regression baseline ``b(s) = βᵀx(s)`` (a context-dependent baseline);
* ``pi2``: PI² per time step: the cost-to-go ``S_k(t)`` minus a per-step baseline ``b_t(s)``, per-step
  weights, a per-step weighted fit ``W(t)``, averaged over time per parameter with weights
  ``(T - t) · activation_i(t)`` (parameters that are never active take the episode-level fit).

The new ``W`` is the weighted maximum-likelihood (MAP) fit ``argmin Σ d_k |u_k - W x_k|² + |(W - W_old) Λ^½|²``,
where the prior ``Λ = diag(0, gain_prior, ...)`` keeps the gains from following a few samples. Each
block's standard deviation is adapted by weighted ML of its whitened sampling noise
(``σ_b² <- (1 - rate) σ_b² + rate Σ d_k |L_b⁻¹ ε_kb|² / m_b``) within ``[min_sigma, MAX_SIGMA]``.
The control cost ``control_cost · ½ Σ_b a_bᵀ A_bᵀA_b a_b`` is added to every sample's cost.
The weighting, whether the gains are learned and whether the returns are seen are the learner's (its
registered name's) own: ``creps``, ``cpibb``, ``cpi2``; ``random`` (contextual REPS fed standard-normal returns: a
control that never sees the reward) and ``amplitude`` (one θ for all contexts, the gains stay 0).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from scipy.optimize import minimize

from rdmp_gym.validation import check_range

from ..config import Settings
from ..registry import register
from .base import EpisodeBatch, Learner, LearnerInputs, cost_weights, ridge_hat
from .credit import remaining_steps, step_credit, weighted_ridge
from .smooth_exploration import SmoothNoise, block_layout, squash, unsquash

__all__ = [
    "MAX_SIGMA",
    "AmplitudeConfig",
    "CPI2Config",
    "CPIBBConfig",
    "CREPSConfig",
    "ContextualConfig",
    "ContextualSearch",
    "ContextualSettings",
    "RandomReturnConfig",
    "SearchSpace",
    "action_layout",
    "group_factors",
    "policy_from_state",
    "select_groups",
]

#: upper bound of each exploration block's standard deviation (times its ``sigma_factors``)
MAX_SIGMA = 0.6
_BUFFER_KEYS = ("u", "noise", "x", "costs", "traces")


@dataclass(frozen=True)
class ContextualSettings(Settings):
    """Settings the contextual learners share (the linear-Gaussian searches here and ``bbrl``).

    Attributes:
        sigma: initial per-weight standard deviation (action units).
        length: correlation length of the exploration in neighbouring weights (0 = isotropic).
        epsilon: the update's KL bound (REPS's dual; ``bbrl``'s trust region).
        h: eliteness of the cost weighting.
        reuse: batches (this one and earlier ones) whose samples enter each update.
        min_sigma: floor of the exploration's standard deviation.
        sigma_factors: per-group factors of ``sigma`` and its bounds (e.g. ``{"approach": 3}``: a dimension whose
            effect is only seen far from the imitation, such as a lift that clears an obstacle only near its full
            height, is explored over its whole range). Choosing factors is task structure.
    """

    sigma: float = 0.3
    length: float = 5.0
    epsilon: float = 1.0
    h: float = 10.0
    reuse: int = 4
    min_sigma: float = 0.02
    sigma_factors: dict[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        check_range(self.sigma, "sigma", 0.0, None, low_open=True)
        check_range(self.length, "length", 0.0, None)
        check_range(self.epsilon, "epsilon", 0.0, None, low_open=True)
        check_range(self.h, "h", 0.0, None, low_open=True)
        check_range(self.reuse, "reuse", 1, None)
        check_range(self.min_sigma, "min_sigma", 0.0, self.sigma)
        for group, factor in self.sigma_factors.items():
            if not np.isfinite(factor) or factor <= 0:
                raise ValueError(f"sigma_factors: {group}={factor!r} is not a factor > 0")


@dataclass(frozen=True)
class ContextualConfig(ContextualSettings):
    """Settings of :class:`ContextualSearch` (beyond :class:`ContextualSettings`; ``sigma`` at most
    :data:`MAX_SIGMA`). The class attributes ``weighting`` (``reps``, ``pibb`` or ``pi2``, see the module docstring),
    ``contextual`` (learn the gains ``K``; False: one θ for every context) and ``random_returns`` (replace every
    return by a standard-normal draw) are each learner's own.

    Attributes:
        groups: the action groups to search (empty = all; e.g. ``["amplitude"]``); the others stay at the start.
            Choosing groups is task structure.
        gain_groups: the searched groups whose actions depend on the context (rows of ``K``);
            the others get one value for every context (``θ̄`` only). Empty = every searched group. Few
            context-dependent dimensions keep the weighted fit of ``K`` well posed with a few dozen samples.
        features: the context fields in ``φ(s)`` (names of the context fields of the env's task contract, e.g.
            the wiping task's ``["patch_size", "obstacle"]``); empty = every field. The rest is left out of the
            policy and baselines.
        control_cost: weight of ``½ aᵀRa`` in the cost.
        gain_prior: ridge ``Λ`` pulling the gains toward their previous value (and of the baselines).
        adapt_rate: rate of the step-size adaptation (0 = fixed exploration).
        fourier_features: ``D`` random Fourier features ``√(2/D) cos(Ω φ(s) + b)`` appended to ``φ(s)`` (0 = a
            policy and baselines linear in the context): with them the policy's mean and the cost baselines are
            smooth nonlinear functions of the raw context (``Ω ~ N(0, 1/fourier_length²)``, ``b ~ U[0, 2π)``,
            drawn once from the learner's generator; no feature is chosen by hand).
        fourier_length: length scale of the Fourier features in standardised context units.
    """

    weighting: ClassVar[str] = "reps"
    contextual: ClassVar[bool] = True
    random_returns: ClassVar[bool] = False
    groups: tuple[str, ...] = ()
    gain_groups: tuple[str, ...] = ()
    features: tuple[str, ...] = ()
    control_cost: float = 0.05
    gain_prior: float = 0.3
    adapt_rate: float = 0.5
    fourier_features: int = 0
    fourier_length: float = 1.0

    def __post_init__(self) -> None:
        super().__post_init__()
        check_range(self.sigma, "sigma", 0.0, MAX_SIGMA, low_open=True)
        check_range(self.fourier_features, "fourier_features", 0, None)
        check_range(self.fourier_length, "fourier_length", 0.0, None, low_open=True)
        check_range(self.control_cost, "control_cost", 0.0, None)
        check_range(self.gain_prior, "gain_prior", 0.0, None, low_open=True)
        check_range(self.adapt_rate, "adapt_rate", 0.0, 1.0)

    @classmethod
    def fixed_values(cls) -> dict[str, Any]:
        return {"weighting": cls.weighting, "contextual": cls.contextual, "random_returns": cls.random_returns,
                "max_sigma": MAX_SIGMA}


@dataclass(frozen=True)
class CREPSConfig(ContextualConfig):
    """Contextual REPS (the defaults)."""


@dataclass(frozen=True)
class CPIBBConfig(ContextualConfig):
    """Contextual PI^BB: episode-level weights over a context-dependent baseline."""

    weighting: ClassVar[str] = "pibb"


@dataclass(frozen=True)
class CPI2Config(ContextualConfig):
    """Contextual PI²: per-step weights over per-step context-dependent baselines."""

    weighting: ClassVar[str] = "pi2"


@dataclass(frozen=True)
class RandomReturnConfig(ContextualConfig):
    """The random-return control: contextual REPS fed standard-normal returns."""

    random_returns: ClassVar[bool] = True


@dataclass(frozen=True)
class AmplitudeConfig(ContextualConfig):
    """The amplitude-only baseline: one shared θ over the ``amplitude`` group (3 numbers), isotropic."""

    contextual: ClassVar[bool] = False
    groups: tuple[str, ...] = ("amplitude",)
    length: float = 0.0


@dataclass(frozen=True)
class SearchSpace:
    """What a contextual learner needs to know about the env's action and context.

    Attributes:
        slices: ``{group: slice}`` of the action (one slice ``{"all": slice(0, n)}`` if the env has no groups).
        n_dims: degrees of freedom of the DMP (weight blocks per group).
        context_center, context_scale: ``[o]`` standardisation of the observation (scale 0 = unused feature).
        time_weights: ``[T, n]`` activation of each action dimension per control step (PI² only), or None.
        context_gate: ``[o]`` int: for a gated feature the index of its 0/1 indicator (the feature is
            ``indicator · (o - centre) / scale``), -1 for the others; None = no gated features.
        context_names: ``[o]`` the context field of each observation entry (e.g. ``patch_size``), or None.
    """

    slices: Mapping[str, slice]
    n_dims: int
    context_center: np.ndarray
    context_scale: np.ndarray
    time_weights: np.ndarray | None = None
    context_gate: np.ndarray | None = None
    context_names: tuple[str, ...] | None = None

    @classmethod
    def from_env(cls, env: Any, observations: np.ndarray) -> SearchSpace:
        """From an env (``unwrapped``: ``dmp``, ``groups``, ``action_time_weights()``) and sample
        observations ``[E, o]`` of its contexts (their mean and standard deviation standardise φ)."""
        base = env.unwrapped
        slices, n_dims = action_layout(env)
        observations = np.asarray(observations, dtype=np.float64)
        gate = _context_gate(env, observations.shape[1])
        center, scale = observations.mean(axis=0), observations.std(axis=0)
        for j in np.flatnonzero(gate >= 0):
            defined = observations[observations[:, gate[j]] > 0.5, j]
            center[j], scale[j] = (defined.mean(), defined.std()) if defined.size > 1 else (0.0, 0.0)
        scale[scale < 1e-9 * (1.0 + np.abs(center))] = 0.0
        weights = base.action_time_weights() if hasattr(base, "action_time_weights") else None
        return cls(slices, n_dims, center, scale, weights, gate if np.any(gate >= 0) else None,
                   _context_names(env, observations.shape[1]))


def action_layout(env: Any) -> tuple[dict[str, slice], int]:
    """``({group: slice}, n_dims)`` of an env's action (``{"all": slice(0, n)}`` and 1 if it has no DMP groups)."""
    base = env.unwrapped
    if hasattr(base, "action_slices"):    # the rhythmic tasks: DMP groups, then the task's own dimensions
        return dict(base.action_slices()), int(base.dmp.n_dims)
    if hasattr(base, "action_map"):       # the wiping envs: DMP groups, then e.g. ``approach``, ``sweep_x``
        return dict(base.action_map.action_slices()), int(base.dmp.n_dims)
    if hasattr(base, "dmp") and hasattr(base, "groups"):
        return dict(base.dmp.param_slices(base.groups)), int(base.dmp.n_dims)
    return {"all": slice(0, int(env.action_space.shape[0]))}, 1


def select_groups(slices: Mapping[str, slice], names: Sequence[str], argument: str) -> dict[str, slice]:
    """The groups of ``slices`` that ``names`` name (``transient`` names every ``transient:k``)."""
    wanted = list(names)
    chosen = {k: v for k, v in slices.items() if k in wanted or k.split(":")[0] in wanted}
    if not chosen:
        raise ValueError(f"{argument}: {wanted!r} selects none of the action's groups {sorted(slices)}")
    return chosen


def group_factors(slices: Mapping[str, slice], factors: Mapping[str, float], argument: str = "sigma_factors"
                  ) -> list[tuple[slice, float]]:
    """``(group slice, factor)`` pairs of ``{group: factor}`` (factors > 0), in the mapping's order."""
    pairs = []
    for name, factor in factors.items():
        if not np.isfinite(factor) or factor <= 0:
            raise ValueError(f"{argument}: {name}={factor!r} is not a factor > 0")
        pairs.extend((group, float(factor)) for group in select_groups(slices, [name], argument).values())
    return pairs


def _block_factors(blocks: list[tuple[slice, bool | None]], slices: Mapping[str, slice],
                   factors: Mapping[str, float]) -> np.ndarray:
    """``[B]`` the ``sigma_factors`` of each exploration block (1 where none is given)."""
    per_block = np.ones(len(blocks))
    for group, factor in group_factors(slices, factors):
        for index, (part, _) in enumerate(blocks):
            if group.start <= part.start < group.stop:
                per_block[index] = factor
    return per_block


def _context_fields(env: Any) -> Mapping[str, tuple[int, int]]:
    """The context fields ``{name: (start, size)}`` of the env's task contract (empty: unnamed).

    The contract is read here, where the env already runs (its package is loaded), rather than imported at the
    top: importing the learners loads neither gymnasium nor MuJoCo.
    """
    from rdmp_gym.envs.contract import contract_of  # the env's package: loaded with the env itself

    return contract_of(env).context_fields


def _context_names(env: Any, size: int) -> tuple[str, ...] | None:
    """``[o]`` the field name of each observation entry (None if the env names no fields)."""
    fields = _context_fields(env)
    if not fields:
        return None
    names = [""] * size
    for name, (start, length) in fields.items():
        for index in range(start, min(start + length, size)):
            names[index] = name
    return tuple(names)


def _context_gate(env: Any, size: int) -> np.ndarray:
    """``[o]`` the indicator index of each gated context feature (-1 = not gated): ArmarWipe-v1's cup
    position (``obstacle_position``) is gated by its presence (``obstacle``), read from the context fields of the
    env's contract; an env without them has none."""
    gate = np.full(size, -1, dtype=np.int64)
    fields = _context_fields(env)
    if fields and "obstacle" in fields and "obstacle_position" in fields:
        start, length = fields["obstacle_position"]
        if start + length <= size:
            gate[start:start + length] = fields["obstacle"][0]
    return gate


def context_features(observations: np.ndarray, center: np.ndarray, scale: np.ndarray,
                     gate: np.ndarray | None) -> np.ndarray:
    """``[E, F]`` the standardised features ``φ(s)`` of observations ``[E, o]`` (the columns with scale > 0;
    gated columns multiplied by their indicator, see :class:`SearchSpace`)."""
    used = scale > 0
    phi = (observations - center) / np.where(used, scale, 1.0)
    if gate is not None:
        gated = gate >= 0
        phi[:, gated] *= observations[:, gate[gated]] > 0.5
    return phi[:, used]


def _draw_fourier(config: ContextualConfig, n_features: int, rng: np.random.Generator
                  ) -> tuple[np.ndarray, np.ndarray]:
    """``(Ω [D, F], b [D])`` of ``config.fourier_features`` random Fourier features (D = 0: nothing is drawn)."""
    count = config.fourier_features if config.contextual else 0
    if count == 0:
        return np.zeros((0, n_features)), np.zeros(0)
    frequencies = rng.normal(0.0, 1.0 / config.fourier_length, (count, n_features))
    return frequencies, rng.uniform(0.0, 2.0 * np.pi, count)


def _regressors(observations: np.ndarray, center: np.ndarray, scale: np.ndarray, gate: np.ndarray | None,
                fourier: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """``[E, 1 + F + D]`` the regressors ``[1, φ(s), √(2/D) cos(Ω φ(s) + b)]`` of observations ``[E, o]`` with the
    random Fourier features ``(Ω [D, F], b [D])`` (D = 0: ``[1, φ(s)]``)."""
    phi = context_features(observations, center, scale, gate)
    frequencies, phases = fourier
    columns = [np.ones((phi.shape[0], 1)), phi]
    if phases.size:
        columns.append(np.sqrt(2.0 / phases.size) * np.cos(phi @ frequencies.T + phases))
    return np.concatenate(columns, axis=1)


def _reps_weights(returns: np.ndarray, features: np.ndarray, epsilon: float) -> np.ndarray:
    """``[N]`` contextual REPS weights of returns ``[N]`` with value features ``[N, F]`` (may be F = 0)."""
    spread = returns.std()
    if spread == 0:
        return np.full(returns.size, 1.0 / returns.size)
    r = (returns - returns.mean()) / spread
    mean_features = features.mean(axis=0)

    def dual(z: np.ndarray) -> tuple[float, np.ndarray]:
        eta, v = np.exp(z[0]), z[1:]
        delta = r - features @ v
        top = delta.max()
        weights = np.exp((delta - top) / eta)
        total = weights.sum()
        log_mean = top / eta + np.log(total / r.size)
        weights /= total
        value = eta * epsilon + mean_features @ v + eta * log_mean + 1e-6 * v @ v
        d_eta = epsilon + log_mean - weights @ delta / eta
        d_v = mean_features - weights @ features + 2e-6 * v
        return float(value), np.concatenate([[d_eta * eta], d_v])

    start = np.zeros(1 + features.shape[1])
    result = minimize(dual, start, jac=True, method="L-BFGS-B",
                      bounds=[(np.log(1e-3), np.log(1e3))] + [(None, None)] * features.shape[1])
    eta, v = np.exp(result.x[0]), result.x[1:]
    delta = r - features @ v
    weights = np.exp((delta - delta.max()) / eta)
    return weights / weights.sum()


class ContextualSearch(Learner):
    """Contextual policy search with smooth exploration, smoothly bounded actions and sample reuse.

    Args:
        initial_mean: ``[n]`` start action (the policy for every context at first).
        rollouts: rollouts per update ``K``.
        rng: the only source of randomness.
        space: the action layout and context standardisation.
        config: the settings.
        name: the learner's registry name (``creps``, ``cpibb``, ``cpi2``, ``random``, ``amplitude``).
    """

    uses_context = True

    def __init__(self, initial_mean: np.ndarray, rollouts: int, rng: np.random.Generator, space: SearchSpace,
                 config: ContextualConfig | None = None, name: str = "creps") -> None:
        super().__init__(initial_mean, rollouts, rng)
        self.config = config or ContextualConfig()
        self.name = name
        slices = dict(space.slices)
        if self.config.groups:
            slices = select_groups(slices, self.config.groups, "groups")
        self.noise = SmoothNoise(self.n_params, block_layout(slices, space.n_dims), self.config.length)
        self._explored = self.noise.mask()
        self._context_dependent = self._explored.copy()
        if self.config.gain_groups:
            self._context_dependent = np.zeros(self.n_params, dtype=bool)
            for index in select_groups(slices, self.config.gain_groups, "gain_groups").values():
                self._context_dependent[index] = True
        self.center = np.asarray(space.context_center, dtype=np.float64)
        scale = np.asarray(space.context_scale, dtype=np.float64)
        if self.center.ndim != 1 or scale.shape != self.center.shape or np.any(scale < 0):
            raise ValueError("space: context_center and context_scale must be 1-D of one length, scale >= 0")
        if self.config.features:
            wanted = set(self.config.features)
            names = space.context_names
            if names is None or not wanted <= set(names):
                raise ValueError(f"features: {self.config.features!r} names fields the env's context does not have "
                                 f"({sorted(set(names or ()) - {''})})")
            scale = np.where(np.isin(np.array(names), list(wanted)), scale, 0.0)
        self._used = scale > 0
        self.scale = scale
        self.gate = None if space.context_gate is None else np.asarray(space.context_gate, dtype=np.int64)
        if self.gate is not None and (self.gate.shape != self.center.shape or np.any(self.gate >= self.center.size)):
            raise ValueError("space: context_gate must have the observation's length with indices < its length")
        self.fourier = _draw_fourier(self.config, int(self._used.sum()), rng)
        n_features = 1 + int(self._used.sum()) + self.fourier[1].size if self.config.contextual else 1
        self.gains = np.zeros((self.n_params, n_features))        # W = [θ̄, K]
        self.gains[:, 0] = unsquash(self._mean)
        self._sigma_factor = _block_factors(self.noise.blocks, slices, self.config.sigma_factors)
        self.sigmas = self.config.sigma * self._sigma_factor
        self.time_weights = None
        if self.config.weighting == "pi2":
            if space.time_weights is None:
                raise ValueError("space.time_weights: contextual PI² needs the activation of each parameter per step")
            weights = np.asarray(space.time_weights, dtype=np.float64)
            if weights.ndim != 2 or weights.shape[1] != self.n_params:
                raise ValueError(f"space.time_weights: expected shape [T, {self.n_params}], got {weights.shape}")
            self.time_weights = remaining_steps(weights)                            # [T, n]
        self._pending: dict[str, np.ndarray] | None = None
        self._buffer: list[dict[str, np.ndarray]] = []

    # ------------------------------------------------------------------ policy
    @classmethod
    def build(cls, initial_mean: np.ndarray, rollouts: int, rng: np.random.Generator, config: ContextualConfig,
              inputs: LearnerInputs) -> ContextualSearch:
        """A contextual search needs the action layout and the context standardisation (``inputs.space``)."""
        if inputs.space is None:
            raise ValueError(f"space: {inputs.name} needs the action layout and context standardisation (SearchSpace)")
        return cls(initial_mean, rollouts, rng, inputs.space, config, name=inputs.name or "creps")

    @property
    def exploration(self) -> float:
        return float(np.mean(self.sigmas))

    def features(self, observations: np.ndarray) -> np.ndarray:
        """``[E, F + 1]`` the regressors ``[1, φ(s)]`` of observations ``[E, o]``."""
        obs = np.asarray(observations, dtype=np.float64)
        if obs.ndim != 2 or obs.shape[1] != self.center.size:
            raise ValueError(f"observations: expected shape [E, {self.center.size}], got {obs.shape}")
        if not np.all(np.isfinite(obs)):
            raise ValueError("observations: contains NaN or infinite values")
        if not self.config.contextual:
            return np.ones((obs.shape[0], 1))
        return _regressors(obs, self.center, self.scale, self.gate, self.fourier)

    def policy_actions(self, observations: np.ndarray) -> np.ndarray:
        """``[E, n]`` the policy's action for each context (no exploration)."""
        return squash(self.features(observations) @ self.gains.T)

    def ask(self, observations: np.ndarray | None = None) -> np.ndarray:
        if observations is None:
            raise ValueError("observations: a contextual learner needs the K contexts of the rollouts")
        x = self.features(observations)
        if x.shape[0] != self.rollouts:
            raise ValueError(f"observations: expected {self.rollouts} contexts, got {x.shape[0]}")
        noise = self.noise.sample(self.sigmas, self.rollouts, self.rng)
        u = x @ self.gains.T + noise
        self._pending = {"u": u, "noise": noise, "x": x}
        return squash(u)

    # ------------------------------------------------------------------ update
    def _update(self, batch: EpisodeBatch) -> None:
        if self._pending is None:
            raise RuntimeError("tell: call ask() first")
        if not np.allclose(squash(self._pending["u"]), batch.actions, rtol=0, atol=1e-6):
            raise ValueError("batch.actions: not the actions returned by the last ask()")
        costs = batch.costs + self.config.control_cost * self.noise.control_cost(batch.actions)
        traces = np.asarray(batch.cost_traces, dtype=np.float64)
        if self.time_weights is not None and traces.shape[1:] != self.time_weights.shape[:1]:
            raise ValueError(f"batch.cost_traces: expected {self.time_weights.shape[0]} steps, got {traces.shape[1:]}")
        if self.config.random_returns:
            costs = self.rng.standard_normal(batch.size)
            traces = self.rng.standard_normal(traces.shape) / np.sqrt(max(traces.shape[1], 1))
        self._buffer.append({**self._pending, "costs": costs, "traces": traces})
        self._buffer = self._buffer[-self.config.reuse:]
        self._pending = None
        data = {key: np.concatenate([b[key] for b in self._buffer]) for key in ("u", "noise", "x", "costs")}
        episode = self._episode_weights(data["costs"], data["x"])
        new = self._fit(data["u"], data["x"], episode[None])[0]
        if self.config.weighting == "pi2":
            new = self._pi2_fit(data, new)
        self.gains = np.where(self._explored[:, None], new, self.gains)
        self._adapt(episode, data["noise"])
        self._mean = squash(self.gains[:, 0])

    def _episode_weights(self, costs: np.ndarray, x: np.ndarray) -> np.ndarray:
        """``[N]`` one weight per sample (REPS, or PI^BB over a ridge baseline; PI²'s episode level too)."""
        if self.config.weighting == "reps":
            return _reps_weights(-costs, x[:, 1:], self.config.epsilon)
        advantage = costs - ridge_hat(x, self.config.gain_prior) @ costs
        return cost_weights(advantage, self.config.h)

    def _fit(self, u: np.ndarray, x: np.ndarray, weights: np.ndarray) -> np.ndarray:
        """``[S, n, F + 1]`` the MAP fits of ``u [N, n]`` on ``x [N, F + 1]`` for ``S`` weightings ``[S, N]``
        (the context-independent dimensions: on the constant alone, their gains stay 0)."""
        fit = weighted_ridge(x, weights, u, self.gains, self.config.gain_prior)
        if np.all(self._context_dependent) or x.shape[1] == 1:
            return fit
        shared = weighted_ridge(x[:, :1], weights, u, self.gains[:, :1], self.config.gain_prior)   # [S, n, 1]
        fit[:, ~self._context_dependent] = 0.0
        fit[:, ~self._context_dependent, :1] = shared[:, ~self._context_dependent]
        return fit

    def _pi2_fit(self, data: dict[str, np.ndarray], episode_fit: np.ndarray) -> np.ndarray:
        """Per-step weighted fits averaged over time with ``(T - t) · activation``; ``[n, F + 1]``."""
        assert self.time_weights is not None
        traces = np.concatenate([b["traces"] for b in self._buffer])                     # [N, T]
        return step_credit(data["costs"], traces, self.config.h, self.time_weights, episode_fit,
                           hat=ridge_hat(data["x"], self.config.gain_prior),
                           per_step=lambda weights: self._fit(data["u"], data["x"], weights))   # [T, n, F+1] fits

    def _adapt(self, weights: np.ndarray, noise: np.ndarray) -> None:
        rate = self.config.adapt_rate
        if rate == 0:
            return
        variance = weights @ self.noise.whitened_energy(noise)                           # [B]
        updated = np.sqrt((1 - rate) * self.sigmas**2 + rate * variance)
        self.sigmas = np.clip(updated, self.config.min_sigma * self._sigma_factor,
                              MAX_SIGMA * self._sigma_factor)

    # ------------------------------------------------------------------ state
    def _extra_state(self) -> dict[str, Any]:
        if self._pending is not None:
            raise RuntimeError("state_dict: an ask() is waiting for its tell()")
        # flat 1-D arrays (rows recovered from "sizes"): an empty buffer then has the same structure as a full one
        buffer = {key: np.concatenate([b[key].ravel() for b in self._buffer]) if self._buffer else np.zeros(0)
                  for key in _BUFFER_KEYS}
        buffer["sizes"] = np.array([b["costs"].size for b in self._buffer], dtype=np.int64)
        state = {"gains": self.gains.copy(), "sigmas": self.sigmas.copy(), "buffer": buffer,
                 "context_center": self.center.copy(), "context_scale": self.scale.copy(),
                 "context_gate": np.full(self.center.size, -1) if self.gate is None else self.gate.copy()}
        if self.fourier[1].size:                     # only then: a linear learner's state is what it always was
            state.update(fourier_frequencies=self.fourier[0].copy(), fourier_phases=self.fourier[1].copy())
        return state

    def _load_extra_state(self, state: dict[str, Any]) -> None:
        gains = np.asarray(state["gains"], dtype=np.float64)
        if gains.shape != self.gains.shape:
            raise ValueError(f"state: gains have shape {gains.shape}, expected {self.gains.shape}")
        gate = np.full(self.center.size, -1) if self.gate is None else self.gate
        if not (np.allclose(state["context_center"], self.center) and np.allclose(state["context_scale"], self.scale)
                and np.array_equal(state.get("context_gate", np.full(self.center.size, -1)), gate)):
            raise ValueError("state: written with another context standardisation")
        if self.fourier[1].size:
            fourier = (np.asarray(state["fourier_frequencies"], dtype=np.float64),
                       np.asarray(state["fourier_phases"], dtype=np.float64))
            if fourier[0].shape != self.fourier[0].shape or fourier[1].shape != self.fourier[1].shape:
                raise ValueError(f"state.fourier_frequencies: expected shape {self.fourier[0].shape}, "
                                 f"got {fourier[0].shape}")
            self.fourier = (fourier[0].copy(), fourier[1].copy())
        self.gains = gains.copy()
        self.sigmas = np.asarray(state["sigmas"], dtype=np.float64).copy()
        buffer = state["buffer"]
        sizes = np.asarray(buffer["sizes"], dtype=np.int64)
        rows, ends = int(sizes.sum()), np.cumsum(sizes)
        table = {}
        for key in _BUFFER_KEYS:
            flat = np.asarray(buffer[key], dtype=np.float64).ravel()
            if rows and flat.size % rows:
                raise ValueError(f"state: buffer.{key} has {flat.size} values, not a multiple of its {rows} rows")
            table[key] = flat if key == "costs" or not rows else flat.reshape(rows, -1)
        self._buffer = [{key: table[key][end - size:end] for key in _BUFFER_KEYS}
                        for size, end in zip(sizes, ends, strict=True)]
        self._pending = None


def policy_from_state(state: Mapping[str, Any], observations: np.ndarray) -> np.ndarray:
    """``[E, n]`` the policy actions of a :class:`ContextualSearch` state (``state_dict()``) for
    observations ``[E, o]``, without rebuilding the learner."""
    gains = np.asarray(state["gains"], dtype=np.float64)
    center = np.asarray(state["context_center"], dtype=np.float64)
    scale = np.asarray(state["context_scale"], dtype=np.float64)
    obs = np.asarray(observations, dtype=np.float64)
    if obs.ndim != 2 or obs.shape[1] != center.size:
        raise ValueError(f"observations: expected shape [E, {center.size}], got {obs.shape}")
    gate = state.get("context_gate")
    x = np.ones((obs.shape[0], 1))
    if gains.shape[1] > 1:
        gate = None if gate is None else np.asarray(gate, dtype=np.int64)
        fourier = (np.asarray(state.get("fourier_frequencies", np.zeros((0, 0))), dtype=np.float64),
                   np.asarray(state.get("fourier_phases", np.zeros(0)), dtype=np.float64))
        x = _regressors(obs, center, scale, gate, fourier)
    return squash(x @ gains.T)


for _name, _config in (("creps", CREPSConfig), ("cpibb", CPIBBConfig), ("cpi2", CPI2Config),
                       ("amplitude", AmplitudeConfig), ("random", RandomReturnConfig)):
    register(_name, _config, ContextualSearch)
