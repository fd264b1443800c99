"""Smooth exploration, its control cost and smooth bounds for DMP weight vectors.

A DMP's weights of one degree of freedom are neighbours along the phase (periodic weights, on a
circle) or along the transient's path (a chain). Isotropic noise on them is white noise along the
movement and gives rough paths. As in STOMP (Kalakrishnan et al. 2011) and PI² with a control cost
(Theodorou et al. 2010), each such block is explored with covariance ``∝ R⁻¹``,
``R = AᵀA + λ I``, where ``A`` is the finite-difference (acceleration) matrix of the block; the
control cost ``½ aᵀ R a`` is what the learners add to the episode cost. ``λ = length⁻⁴`` makes
the noise correlated over about ``length`` neighbouring weights; ``length = 0`` gives isotropic noise.
Single parameters (initial conditions, amplitude factors) are explored independently.

Bounds: learners search an unbounded vector ``u`` and execute ``squash(u)`` in ``(-1, 1)`` (the
identity for ``|u| <= 0.8``, a smooth monotone saturation beyond), so no sample is clipped and the update
sees exactly the function of ``u`` that was evaluated. A monotone map keeps one optimum in ``u``;
reflection at the faces (tried first) makes a mirror optimum beyond a face, and on a quadratic with its
optimum within about one exploration width of a face the mean settled between the two (0.87-0.97 for an
optimum at 0.7 with ``sigma`` 0.6 after 50 updates, test_agents_contextual.py's toy).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["KNEE", "SmoothNoise", "block_layout", "difference_matrix", "smooth_factor", "squash", "unsquash"]

#: |u| below which :func:`squash` is the identity (the imitation's neighbourhood is searched unchanged)
KNEE = 0.8


def squash(u: np.ndarray, knee: float = KNEE) -> np.ndarray:
    """Map ``u`` (any shape) into ``(-1, 1)``: the identity for ``|u| <= knee``, then a smooth (C¹),
    monotone ``tanh`` saturation toward the faces."""
    u = np.asarray(u, dtype=np.float64)
    size = np.abs(u)
    outer = knee + (1.0 - knee) * np.tanh((size - knee) / (1.0 - knee))
    return np.sign(u) * np.where(size <= knee, size, outer)


def unsquash(a: np.ndarray, knee: float = KNEE) -> np.ndarray:
    """Inverse of :func:`squash` for ``a`` in ``[-1, 1]`` (a face itself maps to ``|u| = knee + 10 (1 - knee)``)."""
    a = np.asarray(a, dtype=np.float64)
    size = np.minimum(np.abs(a), knee + (1.0 - knee) * np.tanh(10.0))
    inner = knee + (1.0 - knee) * np.arctanh((np.maximum(size, knee) - knee) / (1.0 - knee))
    return np.sign(a) * np.where(size <= knee, size, inner)


def difference_matrix(size: int, circular: bool) -> np.ndarray:
    """Second-difference matrix ``A`` (``[size, size]`` on a circle, ``[size - 2, size]`` on a chain)."""
    if size < 3:
        raise ValueError(f"size: expected >= 3 weights for a second difference, got {size}")
    rows = size if circular else size - 2
    matrix = np.zeros((rows, size))
    for row in range(rows):
        for offset, value in ((0, 1.0), (1, -2.0), (2, 1.0)):
            matrix[row, (row + offset) % size] = value
    return matrix


def block_layout(slices: Mapping[str, slice], n_dims: int) -> list[tuple[slice, bool | None]]:
    """Split the action's groups into blocks: ``(slice, circular)`` for one DoF's weights, ``(slice, None)``
    for independent parameters.

    Args:
        slices: ``{group: slice}`` of the action (``periodic``, ``transient:k``, ``initial:k``, ``amplitude``).
        n_dims: degrees of freedom (the weights of a group are ``n_dims`` consecutive blocks).
    """
    blocks: list[tuple[slice, bool | None]] = []
    for name, part in slices.items():
        short = name.split(":")[0]
        if short in ("periodic", "transient"):
            size = (part.stop - part.start) // n_dims
            for dim in range(n_dims):
                start = part.start + dim * size
                blocks.append((slice(start, start + size), short == "periodic"))
        else:
            blocks.append((part, None))
    return blocks


class SmoothNoise:
    """Gaussian exploration noise with covariance ``diag(scale_b² C_b)`` per block, ``C_b ∝ R_b⁻¹``.

    Args:
        n: dimension of the searched vector.
        blocks: from :func:`block_layout`; dimensions in no block are not explored.
        length: correlation length in weights (0 = isotropic).

    ``C_b`` is normalised to a mean marginal variance of 1, so a scale ``sigma`` gives an average
    per-weight standard deviation ``sigma`` whatever the shape.
    """

    def __init__(self, n: int, blocks: list[tuple[slice, bool | None]], length: float) -> None:
        if not (np.isfinite(length) and length >= 0):
            raise ValueError(f"length: expected a number >= 0, got {length!r}")
        self.n = int(n)
        self.blocks = blocks
        self.factors: list[np.ndarray] = []   # per block: [m, m] with L Lᵀ = C_b
        self.costs: list[np.ndarray] = []     # per block: [m, m] control-cost matrix (zero for independent)
        for part, circular in blocks:
            m = part.stop - part.start
            if circular is None or length == 0 or m < 3:
                self.factors.append(np.eye(m))
                cost = np.zeros((m, m)) if circular is None or m < 3 else self._acceleration_cost(m, circular)
                self.costs.append(cost)
                continue
            a = difference_matrix(m, circular)
            precision = a.T @ a + length**-4 * np.eye(m)
            covariance = np.linalg.inv(precision)
            covariance /= np.mean(np.diag(covariance))
            self.factors.append(np.linalg.cholesky(0.5 * (covariance + covariance.T)))
            self.costs.append(self._acceleration_cost(m, circular))

    @staticmethod
    def _acceleration_cost(m: int, circular: bool) -> np.ndarray:
        a = difference_matrix(m, circular)
        return a.T @ a

    @property
    def n_blocks(self) -> int:
        """Number of blocks ``B``."""
        return len(self.blocks)

    def mask(self) -> np.ndarray:
        """``[n]`` True where a dimension is explored."""
        mask = np.zeros(self.n, dtype=bool)
        for part, _ in self.blocks:
            mask[part] = True
        return mask

    def sample(self, scales: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
        """``[count, n]`` noise with per-block standard deviation ``scales [B]``."""
        noise = np.zeros((count, self.n))
        normal = rng.standard_normal((count, self.n))
        for (part, _), factor, scale in zip(self.blocks, self.factors, scales, strict=True):
            noise[:, part] = scale * normal[:, part] @ factor.T
        return noise

    def whitened_energy(self, noise: np.ndarray) -> np.ndarray:
        """``[K, B]`` ``‖L_b⁻¹ ε_b‖² / m_b`` of noise ``[K, n]`` (the per-block variance it suggests)."""
        energy = np.zeros((noise.shape[0], self.n_blocks))
        for index, ((part, _), factor) in enumerate(zip(self.blocks, self.factors, strict=True)):
            white = np.linalg.solve(factor, noise[:, part].T)
            energy[:, index] = np.mean(white**2, axis=0)
        return energy

    def control_cost(self, actions: np.ndarray) -> np.ndarray:
        """``[K]`` ``½ Σ_b a_bᵀ AᵀA a_b`` of actions ``[K, n]`` (the squared acceleration of the weights'
        deviation from the imitation, summed over the weight blocks)."""
        total = np.zeros(actions.shape[0])
        for (part, _), cost in zip(self.blocks, self.costs, strict=True):
            block = actions[:, part]
            total += 0.5 * np.einsum("ki,ij,kj->k", block, cost, block)
        return total


def smooth_factor(n: int, slices: Mapping[str, slice], n_dims: int, length: float, symmetric: bool = False
                  ) -> np.ndarray:
    """``[n, n]`` a factor ``L`` of the smooth correlation ``C = L Lᵀ`` of an action (block-diagonal: each DoF's
    weights correlated over about ``length`` neighbours, :class:`SmoothNoise`; the identity elsewhere and for
    ``length = 0``). ``sigma · L ε`` with ``ε ~ N(0, I)`` is smooth exploration of mean standard deviation ~sigma.

    ``symmetric``: the symmetric square root ``C^½`` instead of the Cholesky factor. Every column is then a smooth
    bump about its weight, so ``L z`` is smooth for any ``z`` (a Cholesky column starts with a kink at its
    diagonal, and the last column of a block is a single weight), not only for white noise ``z``."""
    noise = SmoothNoise(n, block_layout(slices, n_dims), length)
    factor = np.eye(n)
    for (part, _), block in zip(noise.blocks, noise.factors, strict=True):
        factor[part, part] = _symmetric_root(block @ block.T) if symmetric else block
    return factor


def _symmetric_root(covariance: np.ndarray) -> np.ndarray:
    """``[m, m]`` the symmetric positive square root of a covariance ``[m, m]``."""
    values, vectors = np.linalg.eigh(covariance)
    return (vectors * np.sqrt(np.maximum(values, 0.0))) @ vectors.T


def exploration_factor(n: int, length: float, space: Any, name: str) -> np.ndarray | None:
    """``[n, n]`` the smooth exploration's factor of a one-θ learner (:func:`smooth_factor`), None for ``length 0``;
    ``space`` (a :class:`~rdmp_gym.agents.learners.contextual.SearchSpace`) gives the action layout."""
    if length <= 0:
        return None
    if space is None:
        raise ValueError(f"space: {name} with length > 0 (smooth exploration) needs the action layout")
    return smooth_factor(n, space.slices, space.n_dims, length)
