"""``bbrl``: a neural contextual episodic learner with a trust region (deep black-box RL, Otto et al. 2022).

The policy maps the raw context ``s`` (every field, standardised) to a Gaussian over the unbounded search vector
``u`` (executed as ``squash(u)``, :mod:`.smooth`):

    u ~ N(mu(s), Sigma),   mu(s) = u0 + D0 L MLP(s)   (the last layer starts at 0: the first policy is u0),
    Sigma = D C D + U U^T,  D = diag(sigma),  C = (1 - rough) C_smooth + rough I,

``C_smooth`` the correlation of neighbouring DMP weights (:mod:`.smooth`), the per-dimension scales ``sigma``
and the low-rank factor ``U [n, r]`` learned, shared by all contexts (``context_scale``: times ``scale(s)^2``, a
further output of the network); ``L`` is the Cholesky factor of ``C`` and
``D0`` the initial ``D``, so the network works in whitened coordinates (``linear``: plus a linear map
``W s`` of the context beside the MLP, zero at the start, so that the mean carries beyond the contexts seen as a
linear policy does, where the MLP's tanh units flatten): an optimiser step of equal size
in every output is a step shaped like the exploration (smooth), not a rough one. The ``rough`` share keeps ``C``
well conditioned: under a purely smooth ``C`` a mean step that is not smooth costs a KL divergence of
thousands (the conditional variances of a smooth block are tiny) and the trust region would forbid it.
Exploration is therefore smooth in time from the first update on, and the low-rank part (``rank`` > 0; none
by default) can learn which directions to explore together.

One update, from the samples of the last ``reuse`` batches ``(s_k, u_k, J_k, c_k(t))`` (``J`` the episode cost,
``c(t)`` its per-control-step part):

1. **credit** (PI², Theodorou et al. 2010, per context): the cost-to-go ``S_k(t)`` minus a ridge regression of it on
   the context gives per-step weights ``P_k(t) = exp(-h Â_k(t))`` (normalised over the samples); each action
   dimension ``i`` gets ``d_ik = sum_t a_i(t) P_k(t) / sum_t a_i(t)`` from its activation ``a_i(t)`` over time (the
   env's ``action_time_weights``; ``step_weighting="remaining"``: times ``T - t``, as PI² averages its per-step
   updates, so that the steps whose cost-to-go covers most of the episode count most), so a weight that acts early
   is judged by what happened from then on. Dimensions
   that are never active, and tasks without a cost trace (``credit="episode"``), get the episode-level weights.
   With ``baseline="network"`` a second MLP ``V(s)`` of the cost-to-go, fitted to the ``history`` batches before
   the reused ones (never to the samples it judges), is subtracted first (the ridge then removes what is left,
   e.g. the drift of the policy): a context whose cost no linear function of the context predicts (a cup right on
   the approach) is then judged against what such contexts usually cost, not against every other context;
2. **weighted maximum likelihood** (the M-step of MPO, Abdolmaleki et al. 2018): ``epochs`` Adam steps on
   ``1/2 sum_ik d_ik ((u_ki - mu_i(s_k)) / sigma_i)^2 / n`` for the mean network and the episode-weighted
   negative log-likelihood of the samples around the old means for ``sigma`` and ``U``;
   With ``linear_fit="ridge"`` the mean has an affine part ``b + B s`` (in action units, not whitened) fitted
   before the network, in closed form: each action dimension's weighted ridge regression of what the network
   leaves, ``u_ki - (mu_i(s_k) - b_i - B_i s_k)``, on ``[1, s_k]`` with its weights ``d_ik``, ``B`` pulled towards
   its previous value by ``linear_prior`` (as ``cpi2`` fits its gains); the network then fits what is left;
3. the **trust region**: the mean KL divergence ``KL(p_old(.|s) || p_new(.|s))`` over the samples' contexts must
   not exceed ``epsilon``; the step is shrunk towards the old parameters (halving its length, up to 20 times,
   else dropped) until it does. The bound holds by construction, not only on average as with a clipped ratio.

No task-specific structure: no hand-picked groups, gains or features. Randomness comes only from the
learner's numpy Generator (torch is seeded from it per update), so resuming from a checkpoint is exact.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import torch

from .base import EpisodeBatch, Learner, LearnerInputs, cost_to_go, cost_weights, ridge_hat
from .bbrl_config import BASELINES, CREDITS, VALUE_RIDGE, BBRLConfig
from .contextual import SearchSpace, group_factors
from .credit import remaining_steps, step_credit, weighted_ridge
from .smooth_exploration import smooth_factor, squash, unsquash

__all__ = ["BASELINES", "BBRL", "CREDITS", "BBRLConfig", "bbrl_policy_actions", "sample_weights"]

_DTYPE = torch.float64
#: the low-rank factor's entries start at this share of each dimension's sigma (times a standard normal draw)
LOW_RANK_START = 0.01
_BUFFER = ("contexts", "samples", "costs", "traces")


def sample_weights(costs: np.ndarray, traces: np.ndarray | None, contexts: np.ndarray,
                   time_weights: np.ndarray | None, h: float, ridge: float,
                   predicted: np.ndarray | None = None, paired: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Per-dimension and episode-level weights of ``N`` samples (step 1 of the module docstring).

    Args:
        costs: ``[N]`` episode costs; traces: ``[N, T]`` their per-step parts, or None.
        contexts: ``[N, o]`` standardised contexts (the baselines' regressors).
        time_weights: ``[T, n]`` activation of each action dimension per control step, or None.
        h: eliteness; ridge: ridge of the baselines.
        predicted: ``[N, T]`` (``[N, 1]`` without traces) a baseline of the cost-to-go subtracted before the
            ridge (column 0: of the episode cost), or None.
        paired: the samples are antithetic pairs (rows 2i, 2i + 1 share a context): each pair's mean is the
            baseline, in place of the ridge.
    Returns:
        ``([n, N] or [1, N], [N])``: each row sums to 1 (``[1, N]``, the episode weights, without per-step credit).
    """
    hat = pair_hat(len(costs)) if paired else ridge_hat(np.c_[np.ones(len(costs)), contexts], ridge)
    offset = np.zeros((len(costs), 1)) if predicted is None else np.asarray(predicted, dtype=np.float64)
    episode = cost_weights(cost_advantage(costs, hat, offset[:, 0]), h)
    if traces is None or time_weights is None:
        return episode[None], episode
    return step_credit(costs, traces, h, time_weights, episode[None], hat=hat, offset=offset), episode


def pair_hat(n: int) -> np.ndarray:
    """``[n, n]`` the matrix that replaces each of ``n`` (even) values by the mean of its pair (rows 2i, 2i + 1)."""
    if n % 2:
        raise ValueError(f"n: antithetic samples come in pairs, got {n} samples")
    return np.kron(np.eye(n // 2), np.full((2, 2), 0.5))


def cost_advantage(costs: np.ndarray, hat: np.ndarray, predicted: np.ndarray) -> np.ndarray:
    """``[N]`` how much more each sample cost than its context predicts: ``costs [N]`` minus the baseline
    ``predicted [N]``, minus the ridge fit ``hat [N, N]`` of what is left on the context."""
    residual = costs - predicted
    return residual - hat @ residual


def value_targets(costs: np.ndarray, traces: np.ndarray | None, credit: bool) -> np.ndarray:
    """``[N, T]`` the cost-to-go of each step (``credit``, with traces), else ``[N, 1]`` the episode costs."""
    return cost_to_go(costs, traces) if credit and traces is not None else np.asarray(costs, dtype=np.float64)[:, None]


class _Value(torch.nn.Module):
    """``V(s)``: ``[K, o]`` standardised contexts to ``[K, T]`` cost-to-go, in units of ``scale`` about ``offset``."""

    def __init__(self, n_context: int, hidden: int, n_out: int) -> None:
        super().__init__()
        self.net = torch.nn.Sequential(torch.nn.Linear(n_context, hidden), torch.nn.Tanh(),
                                       torch.nn.Linear(hidden, hidden), torch.nn.Tanh(), torch.nn.Linear(hidden, n_out))
        torch.nn.init.zeros_(self.net[-1].weight)
        torch.nn.init.zeros_(self.net[-1].bias)
        self.register_buffer("offset", torch.zeros(n_out, dtype=_DTYPE))
        self.register_buffer("scale", torch.ones((), dtype=_DTYPE))
        self.to(_DTYPE)

    def forward(self, contexts: torch.Tensor) -> torch.Tensor:
        return self.offset + self.scale * self.net(contexts)

    def fit(self, contexts: torch.Tensor, targets: torch.Tensor, epochs: int, learning_rate: float) -> None:
        """``epochs`` Adam steps on the mean squared error, from the current weights; the targets' mean and
        spread set ``offset`` and ``scale`` first."""
        with torch.no_grad():
            self.offset.copy_(targets.mean(dim=0))
            self.scale.copy_(torch.clamp(targets.std(), min=1e-9) if len(targets) > 1 else torch.ones((), dtype=_DTYPE))
        optimizer = torch.optim.Adam(self.net.parameters(), lr=learning_rate)
        for _ in range(epochs):
            optimizer.zero_grad()
            loss = torch.mean(((self(contexts) - targets) / self.scale) ** 2)
            loss.backward()
            optimizer.step()


class _Policy(torch.nn.Module):
    """``mu(s) = u0 + D0 L (MLP(s) + W s) + b + B s`` (``W s`` with ``linear`` only, ``b + B s`` with ``affine``
    only) and ``Sigma = D C D + U U^T`` (see the module docstring)."""

    def __init__(self, u0: np.ndarray, n_context: int, hidden: int, correlation: np.ndarray, sigma: np.ndarray,
                 rank: int, context_scale: bool = False, linear: bool = False, affine: bool = False) -> None:
        super().__init__()
        n = u0.size
        self.n = n
        self.net = torch.nn.Sequential(torch.nn.Linear(n_context, hidden), torch.nn.Tanh(),
                                       torch.nn.Linear(hidden, hidden), torch.nn.Tanh(),
                                       torch.nn.Linear(hidden, n + int(context_scale)))
        torch.nn.init.zeros_(self.net[-1].weight)
        torch.nn.init.zeros_(self.net[-1].bias)
        #: the linear part of the mean (None without ``linear``): it carries the mean beyond the contexts seen
        self.linear = torch.nn.Linear(n_context, n, bias=False) if linear else None
        if self.linear is not None:
            torch.nn.init.zeros_(self.linear.weight)
        #: ``[n, 1 + o]`` the affine part ``[b, B]`` (None without ``affine``), fitted in closed form, not by Adam
        self.affine = (torch.nn.Parameter(torch.zeros(n, n_context + 1, dtype=_DTYPE), requires_grad=False)
                       if affine else None)
        self.register_buffer("u0", torch.as_tensor(u0))
        self.register_buffer("correlation", torch.as_tensor(correlation))
        sigma = torch.as_tensor(np.broadcast_to(sigma, (n,)).copy(), dtype=_DTYPE)
        self.register_buffer("shape", sigma[:, None] * torch.linalg.cholesky(torch.as_tensor(correlation)))
        self.log_sigma = torch.nn.Parameter(torch.log(sigma))
        # a small random start: at U = 0 the gradient of U U^T is zero, so U would never move
        self.low_rank = torch.nn.Parameter(LOW_RANK_START * sigma[:, None] * torch.randn(n, rank, dtype=_DTYPE))
        self.to(_DTYPE)

    def mean(self, contexts: torch.Tensor) -> torch.Tensor:
        """``[K, n]`` means for standardised contexts ``[K, o]``."""
        out = self.net(contexts)[:, : self.n]
        if self.linear is not None:
            out = out + self.linear(contexts)
        mean = self.u0 + out @ self.shape.T
        if self.affine is not None:
            mean = mean + self.affine[:, 0] + contexts @ self.affine[:, 1:].T
        return mean

    def log_scale(self, contexts: torch.Tensor) -> torch.Tensor:
        """``[K]`` the log exploration scale of each context (0 without ``context_scale``, with no network pass)."""
        if self.net[-1].out_features == self.n:
            return torch.zeros(len(contexts), dtype=_DTYPE)
        return self.net(contexts)[:, self.n]

    def covariance(self, min_sigma: float) -> torch.Tensor:
        """``[n, n]`` the shared covariance."""
        sigma = torch.clamp(torch.exp(self.log_sigma), min=min_sigma)
        return sigma[:, None] * self.correlation * sigma[None, :] + self.low_rank @ self.low_rank.T


def _log_prob(u: torch.Tensor, mean: torch.Tensor, chol: torch.Tensor, log_scale: torch.Tensor) -> torch.Tensor:
    """``[K]`` Gaussian log densities of ``u [K, n]`` (up to the constant) under means ``[K, n]`` and covariances
    ``exp(2 log_scale_k) Sigma`` (``log_scale [K]``, ``chol`` of Sigma)."""
    white = torch.linalg.solve_triangular(chol, (u - mean).T, upper=False) * torch.exp(-log_scale)
    return (-0.5 * torch.sum(white**2, dim=0) - torch.sum(torch.log(torch.diagonal(chol)))
            - mean.shape[1] * log_scale)


def gaussian_kl(mean_old: torch.Tensor, chol_old: torch.Tensor, mean_new: torch.Tensor, chol_new: torch.Tensor,
                scale_old: torch.Tensor | None = None, scale_new: torch.Tensor | None = None) -> torch.Tensor:
    """``[K]`` ``KL(N(mean_old, a^2 Sigma_old) || N(mean_new, b^2 Sigma_new))`` per row of the means ``[K, n]``,
    ``a``, ``b`` the log scales ``[K]`` ``scale_old``, ``scale_new`` (None: 0)."""
    n = mean_old.shape[1]
    zeros = torch.zeros(mean_old.shape[0], dtype=mean_old.dtype)
    a = zeros if scale_old is None else scale_old
    b = zeros if scale_new is None else scale_new
    trace = torch.sum(torch.linalg.solve_triangular(chol_new, chol_old, upper=False) ** 2) * torch.exp(2.0 * (a - b))
    white = torch.linalg.solve_triangular(chol_new, (mean_new - mean_old).T, upper=False) * torch.exp(-b)
    log_det = 2.0 * (torch.sum(torch.log(torch.diagonal(chol_new))) - torch.sum(torch.log(torch.diagonal(chol_old))))
    return 0.5 * (trace + torch.sum(white**2, dim=0) - n + log_det + 2.0 * n * (b - a))


class BBRL(Learner):
    """The neural contextual learner of the module docstring.

    Args:
        initial_mean: ``[n]`` start action (``squash(u0)``; 0 = the imitation).
        rollouts: episodes per update ``K``.
        rng: the only source of randomness.
        space: the action layout (for the smooth correlation) and the context standardisation.
        config: :class:`BBRLConfig`.
    """

    name = "bbrl"
    uses_context = True

    def __init__(self, initial_mean: np.ndarray, rollouts: int, rng: np.random.Generator, space: SearchSpace,
                 config: BBRLConfig | None = None) -> None:
        super().__init__(initial_mean, rollouts, rng)
        self.config = config or BBRLConfig()
        if self.config.antithetic and rollouts % 2:
            raise ValueError(f"rollouts: antithetic sampling needs an even number of rollouts, got {rollouts}")
        self.space = space
        self.center, self.scale = np.asarray(space.context_center), np.asarray(space.context_scale)
        factor = smooth_factor(self.n_params, space.slices, space.n_dims, self.config.length)
        correlation = (1.0 - self.config.rough) * (factor @ factor.T) + self.config.rough * np.eye(self.n_params)
        torch.manual_seed(int(rng.integers(2**31)))
        self.policy = _Policy(unsquash(self._mean), self.center.size, self.config.hidden, correlation,
                              self._initial_sigma(space), self.config.rank, self.config.context_scale,
                              self.config.linear and self.config.linear_fit == "adam",
                              self.config.linear and self.config.linear_fit == "ridge")
        self.time_weights = self._time_weights(space) if self.config.credit == "step" else None
        #: the cost-to-go baseline network (``baseline="network"``), else None
        self.value = (_Value(self.center.size, self.config.hidden, self._value_outputs())
                      if self.config.baseline == "network" else None)
        self._asked: tuple[np.ndarray, np.ndarray] | None = None      # (contexts [K, o], u [K, n])
        #: the samples of the last ``reuse`` (and ``history``) batches: contexts [N, o], samples [N, n], costs [N],
        #: traces [N, T]
        self._buffer: list[dict[str, np.ndarray]] = []
        self._kept = self.config.reuse + (self.config.history - 1 if self.value is not None else 0)
        #: the mean KL divergence of the last update (after the trust region)
        self.last_kl = 0.0

    @classmethod
    def build(cls, initial_mean: np.ndarray, rollouts: int, rng: np.random.Generator, config: BBRLConfig,
              inputs: LearnerInputs) -> BBRL:
        """``bbrl`` needs the action layout and the context standardisation (``inputs.space``)."""
        if inputs.space is None:
            raise ValueError("space: bbrl needs the action layout and context standardisation (SearchSpace)")
        return cls(initial_mean, rollouts, rng, inputs.space, config)

    def _initial_sigma(self, space: SearchSpace) -> np.ndarray:
        """``[n]`` the initial standard deviation of each action dimension (``sigma`` x its factor)."""
        sigma = np.full(self.n_params, self.config.sigma)
        for group, factor in group_factors(space.slices, self.config.sigma_factors):
            sigma[group] = self.config.sigma * factor
        return sigma

    def _time_weights(self, space: SearchSpace) -> np.ndarray | None:
        if space.time_weights is None:
            return None
        weights = np.asarray(space.time_weights, dtype=np.float64)
        if weights.ndim != 2 or weights.shape[1] != self.n_params:
            raise ValueError(f"space.time_weights: expected shape [T, {self.n_params}], got {weights.shape}")
        if self.config.step_weighting == "remaining":
            weights = remaining_steps(weights)
        return np.asfortranarray(weights)      # column-major: the credit's sums over the steps run in this order

    # ------------------------------------------------------------------ sampling
    def _features(self, observations: np.ndarray) -> np.ndarray:
        obs = np.asarray(observations, dtype=np.float64)
        if obs.ndim != 2 or obs.shape[1] != self.center.size:
            raise ValueError(f"observations: expected shape [K, {self.center.size}], got {obs.shape}")
        safe = np.where(self.scale > 0, self.scale, 1.0)
        return np.where(self.scale > 0, (obs - self.center) / safe, 0.0)

    def _chol(self) -> torch.Tensor:
        return torch.linalg.cholesky(self.policy.covariance(self.config.min_sigma))

    @property
    def exploration(self) -> float:
        """Mean standard deviation of the exploration over the dimensions, at the centre of the contexts."""
        with torch.no_grad():
            scale = torch.exp(self.policy.log_scale(torch.zeros(1, self.center.size, dtype=_DTYPE)))[0]
            return float(scale * torch.mean(torch.sqrt(torch.diagonal(self.policy.covariance(self.config.min_sigma)))))

    def ask(self, observations: np.ndarray | None = None) -> np.ndarray:
        if observations is None:
            raise ValueError("observations: bbrl is contextual; ask needs the rollouts' contexts [K, o]")
        x = self._features(observations)
        if x.shape[0] != self.rollouts:
            raise ValueError(f"observations: expected {self.rollouts} rows, got {x.shape[0]}")
        if self.config.antithetic and not np.array_equal(x[0::2], x[1::2]):
            raise ValueError("observations: antithetic sampling needs rows 2i and 2i + 1 to be the same context "
                             "(choose_seeds pairs the reset seeds)")
        with torch.no_grad():
            mean = self.policy.mean(torch.as_tensor(x)).numpy()
            scale = torch.exp(self.policy.log_scale(torch.as_tensor(x))).numpy()
            chol = self._chol().numpy()
        u = mean + scale[:, None] * (self._noise() @ chol.T)
        self._asked = (x, u)
        return squash(u)

    def _noise(self) -> np.ndarray:
        """``[K, n]`` standard normal perturbations; antithetic: rows ``2i`` and ``2i + 1`` opposite."""
        if not self.config.antithetic:
            return self.rng.standard_normal((self.rollouts, self.n_params))
        half = self.rng.standard_normal((self.rollouts // 2, self.n_params))
        return np.stack([half, -half], axis=1).reshape(self.rollouts, self.n_params)

    def choose_seeds(self, fresh: np.ndarray) -> np.ndarray:
        """``[K]`` the reset seeds: ``fresh``; antithetic: the first ``K / 2`` of ``fresh``, each twice in a row."""
        seeds = np.array(fresh, dtype=np.int64)
        return np.repeat(seeds[: seeds.size // 2], 2) if self.config.antithetic else seeds

    def policy_actions(self, observations: np.ndarray) -> np.ndarray:
        with torch.no_grad():
            return squash(self.policy.mean(torch.as_tensor(self._features(observations))).numpy())

    # ------------------------------------------------------------------ update
    def _update(self, batch: EpisodeBatch) -> None:
        if self._asked is None:
            raise RuntimeError("tell: call ask first")
        x, u = self._asked
        traces = np.asarray(batch.cost_traces, dtype=np.float64)
        if self.time_weights is not None and traces.shape[1] != self.time_weights.shape[0]:
            raise ValueError(f"batch.cost_traces: expected {self.time_weights.shape[0]} steps, got {traces.shape[1]}")
        self._buffer = [*self._buffer, {"contexts": x, "samples": u, "costs": batch.costs.copy(),
                                        "traces": traces}][-self._kept:]
        data = {key: np.concatenate([b[key] for b in self._buffer[-self.config.reuse:]]) for key in _BUFFER}
        predicted = None
        if self.value is not None:
            with torch.no_grad():
                predicted = self.value(torch.as_tensor(data["contexts"])).numpy()
        per_dimension, episode = self._sample_weights(data, predicted)
        torch.manual_seed(int(self.rng.integers(2**31)))
        contexts, samples = torch.as_tensor(data["contexts"]), torch.as_tensor(data["samples"])
        old = [p.detach().clone() for p in self.policy.parameters()]
        with torch.no_grad():
            old_mean, old_chol = self.policy.mean(contexts), self._chol()
            old_scale = self.policy.log_scale(contexts)
        if self.policy.affine is not None:
            self._fit_affine(contexts, samples, per_dimension, old_mean)
        self._maximise_likelihood(contexts, samples, torch.as_tensor(per_dimension), torch.as_tensor(episode),
                                  old_mean)
        self.last_kl = self._enforce_trust_region(old, contexts, old_mean, old_chol, old_scale)
        self._mean = self.policy_actions(self.center[None])[0]
        self._asked = None
        if self.value is not None:
            self._fit_value()

    def _value_outputs(self) -> int:
        """Outputs of the baseline network: the cost-to-go of every step (per-step credit), else the cost."""
        return 1 if self.time_weights is None else self.time_weights.shape[0]

    def _sample_weights(self, data: dict[str, np.ndarray],
                        predicted: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        """``([n or 1, N], [N])`` the per-dimension and episode weights of the reused samples ``data`` (step 1)."""
        return sample_weights(data["costs"], data["traces"], data["contexts"], self.time_weights, self.config.h,
                              VALUE_RIDGE, predicted, paired=self.config.antithetic)

    def _value_targets(self, batch: dict[str, np.ndarray]) -> np.ndarray:
        """``[K, T or 1]`` what the baseline network predicts of one stored batch (its cost-to-go, or its cost)."""
        return value_targets(batch["costs"], batch["traces"], self.time_weights is not None)

    def _fit_value(self) -> None:
        """Fit the baseline network, for the next update, to the cost-to-go of ``history`` batches older than the
        next update's samples (a network fitted to a sample would explain its own cost away)."""
        older = self._buffer[: len(self._buffer) - (self.config.reuse - 1)][-self.config.history:]
        if not older:
            return
        contexts = torch.as_tensor(np.concatenate([b["contexts"] for b in older]))
        targets = np.concatenate([self._value_targets(b) for b in older])
        self.value.fit(contexts, torch.as_tensor(targets), self.config.value_epochs, self.config.learning_rate)

    def _maximise_likelihood(self, contexts: torch.Tensor, samples: torch.Tensor, per_dimension: torch.Tensor,
                             episode: torch.Tensor, old_mean: torch.Tensor) -> None:
        """Step 2: Adam on the weighted mean regression ``[n or 1, N]`` weights and the covariance's weighted NLL."""
        optimizer = torch.optim.Adam(self.policy.parameters(), lr=self.config.learning_rate)
        for _ in range(self.config.epochs):
            optimizer.zero_grad()
            chol = self._chol()
            scale = torch.sqrt(torch.sum(chol**2, dim=1)).detach()                       # [n] marginal sigmas
            residual = ((samples - self.policy.mean(contexts)) / scale) ** 2             # [N, n]
            mean_loss = 0.5 * torch.sum(per_dimension.T * residual) / samples.shape[1]
            log_prob = _log_prob(samples, old_mean, chol, self.policy.log_scale(contexts))
            cov_loss = -torch.sum(episode * log_prob) / samples.shape[1]
            (mean_loss + cov_loss).backward()
            optimizer.step()

    def _fit_affine(self, contexts: torch.Tensor, samples: torch.Tensor, weights: np.ndarray,
                    mean: torch.Tensor) -> None:
        """Step 2 with ``linear_fit="ridge"``: the affine part ``[b, B] [n, 1 + o]`` by each dimension's weighted
        ridge regression (weights ``[n or 1, N]``) of what the rest of the current mean ``[N, n]`` leaves of the
        samples ``[N, n]`` on ``[1, s]`` (contexts ``[N, o]``), ``B`` pulled towards its previous value."""
        previous = self.policy.affine.detach().numpy()
        x = np.c_[np.ones(len(contexts)), contexts.numpy()]                             # [N, 1 + o]
        rest = (samples - mean).numpy() + x @ previous.T                                # [N, n]
        weights = np.broadcast_to(weights, (previous.shape[0], len(x)))                 # [n, N]
        fit = weighted_ridge(x, weights, rest, previous, self.config.linear_prior, per_dimension=True)
        with torch.no_grad():
            self.policy.affine.copy_(torch.as_tensor(fit))

    def _kl(self, contexts: torch.Tensor, old_mean: torch.Tensor, old_chol: torch.Tensor,
            old_scale: torch.Tensor) -> float:
        with torch.no_grad():
            return float(torch.mean(gaussian_kl(old_mean, old_chol, self.policy.mean(contexts), self._chol(),
                                                old_scale, self.policy.log_scale(contexts))))

    def _enforce_trust_region(self, old: list[torch.Tensor], contexts: torch.Tensor, old_mean: torch.Tensor,
                              old_chol: torch.Tensor, old_scale: torch.Tensor) -> float:
        """Shrink the step until the mean KL is within ``epsilon`` (or drop it); returns the final mean KL."""
        new = [p.detach().clone() for p in self.policy.parameters()]
        fraction = 1.0
        for _ in range(20):
            kl = self._kl(contexts, old_mean, old_chol, old_scale)
            if np.isfinite(kl) and kl <= self.config.epsilon:
                return kl
            fraction *= 0.5
            with torch.no_grad():
                for param, start, end in zip(self.policy.parameters(), old, new, strict=True):
                    param.copy_(start + fraction * (end - start))
        with torch.no_grad():
            for param, start in zip(self.policy.parameters(), old, strict=True):
                param.copy_(start)
        return 0.0

    # ------------------------------------------------------------------ state
    def _extra_state(self) -> dict[str, Any]:
        buffer = {f"buffer_{key}": [b[key].copy() for b in self._buffer] for key in _BUFFER}
        return {"parameters": {name: value.detach().numpy().copy() for name, value in self.policy.state_dict().items()},
                "context_center": self.center.copy(), "context_scale": self.scale.copy(), **buffer,
                "min_sigma": float(self.config.min_sigma),
                **({} if self.value is None else {"value_parameters": {
                    name: value.detach().numpy().copy() for name, value in self.value.state_dict().items()}})}

    def _load_extra_state(self, state: dict[str, Any]) -> None:
        parameters = {name: torch.as_tensor(np.asarray(value, dtype=np.float64))
                      for name, value in state["parameters"].items()}
        shapes = {name: tuple(value.shape) for name, value in self.policy.state_dict().items()}
        if {name: tuple(value.shape) for name, value in parameters.items()} != shapes:
            raise ValueError("state.parameters: the state's policy network has other shapes than this learner's "
                             "(hidden, rank, context_scale, linear or linear_fit differ)")
        self.policy.load_state_dict(parameters)
        if self.value is not None:             # a state of the other baseline fails check_state_like's keys
            self.value.load_state_dict({name: torch.as_tensor(np.asarray(value, dtype=np.float64))
                                        for name, value in state["value_parameters"].items()})
        columns = [state[f"buffer_{key}"] for key in _BUFFER]
        if len({len(c) for c in columns}) != 1 or len(columns[0]) > self._kept:
            raise ValueError("state.buffer_contexts: expected as many batches in every buffer field, at most "
                             "reuse (or history)")
        self._buffer = [{key: np.asarray(value, dtype=np.float64) for key, value in zip(_BUFFER, batch, strict=True)}
                        for batch in zip(*columns, strict=True)]
        self._asked = None


def bbrl_policy_actions(state: Mapping[str, Any], observations: np.ndarray) -> np.ndarray:
    """``[E, n]`` the policy actions of a :class:`BBRL` state (``state_dict()``) for observations ``[E, o]``,
    without rebuilding the learner (the mean network evaluated in numpy)."""
    params = {name: np.asarray(value, dtype=np.float64) for name, value in state["parameters"].items()}
    center = np.asarray(state["context_center"], dtype=np.float64)
    scale = np.asarray(state["context_scale"], dtype=np.float64)
    obs = np.asarray(observations, dtype=np.float64)
    if obs.ndim != 2 or obs.shape[1] != center.size:
        raise ValueError(f"observations: expected shape [E, {center.size}], got {obs.shape}")
    x = np.where(scale > 0, (obs - center) / np.where(scale > 0, scale, 1.0), 0.0)
    hidden = np.tanh(x @ params["net.0.weight"].T + params["net.0.bias"])
    hidden = np.tanh(hidden @ params["net.2.weight"].T + params["net.2.bias"])
    n = params["u0"].size                                   # a context_scale network has one more output
    out = hidden @ params["net.4.weight"][:n].T + params["net.4.bias"][:n]
    if "linear.weight" in params:                            # the linear part of the mean
        out = out + x @ params["linear.weight"].T
    policy = params["u0"] + out @ params["shape"].T
    if "affine" in params:                                   # the affine part fitted in closed form
        policy = policy + params["affine"][:, 0] + x @ params["affine"][:, 1:].T
    return squash(policy)
