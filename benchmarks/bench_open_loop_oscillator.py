"""The open-loop oscillator baseline (Raffin et al. 2024), re-implemented here and tuned by CMA-ES at equal steps.

The policy, written from the paper's description (An Open-Loop Baseline for Reinforcement Learning Locomotion Tasks,
arXiv 2310.05808): one oscillator per actuated joint, ``q_des_j = a_j sin(theta_j + phi_j) + b_j``, whose phase
``theta_j`` (0 at the reset) runs at ``2 pi f_swing`` while ``sin(theta_j + phi_j) > 0`` and at ``2 pi f_stance``
otherwise (the swing/stance split; without it one frequency ``f`` for all joints), tracked by a PD controller onto
the torques, ``clip(kp (q_des - q) - kd qd, low, high)``, the desired state taken at the start of each env step.
The parameters per env: amplitude, phase and offset per joint and the frequencies (:data:`ENVS`: Swimmer-v5 with one
frequency, 7 numbers; HalfCheetah-v5 with the split, 20 numbers), in boxes derived from the joints' ranges
(:class:`OscillatorSpace`); the PD gains are fixed, the authors' (Swimmer 10 / 0.5, HalfCheetah 1 / 0.05).

CMA-ES (the ``cma`` package, population 10, sigma 0.5 in the unit box ``[-1, 1]^n``, start at its centre) evaluates
each candidate on one episode of 1000 env steps from a training reset seed; the budget is 100k env steps (10
generations of 10 episodes), as the locomotion study's learners (``bench_locomotion.py``). After each generation
(every 10k env steps) CMA-ES's mean is evaluated on the 3 validation contexts, and at the end on the 10 test contexts
of :mod:`rdmp_gym.agents.protocol` (those evaluations are not counted in the budget). Per seed: the best training
episode's return ("best"), the final mean's test return ("final"), the best candidate's test return ("best_test"),
the curve, and the seconds the training took (wall clock and process CPU; the evaluations apart). The summary: the
interquartile mean over seeds with its 95 % percentile-bootstrap interval (``rdmp_gym.agents.protocol.interval``,
fixed seed).

The reference rows, on reset seeds 0-9: the authors' published Swimmer oscillator (0.62 Hz, phases 0 and
0.95 x 2 pi, amplitude 1 rad, PD 10 / 0.5; the code on their RLC 2024 slides), and the rhythmic black-box wrapper's
default pattern (``make_blackbox(env_id)``, action 0) with the other patterns of :data:`ALTERNATIVES` and the raw zero
action beside it.

One JSON per (env, seed) under ``--run-dir``: a finished seed is skipped, so an interrupted run resumes. One process
(the CPU is shared), ``OMP_NUM_THREADS=1``. About 20-30 s of CPU per seed and env on one core.

    python benchmarks/bench_open_loop_oscillator.py --split env off --save   # 10 seeds x 2 envs, and HalfCheetah
                                                                              # with one frequency
    python benchmarks/bench_open_loop_oscillator.py --envs Swimmer-v5 --seeds 0 1 --run-dir /tmp/osc
    python benchmarks/bench_open_loop_oscillator.py --split env off --summary-only --save   # the finished seeds
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import json
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cma
import gymnasium as gym
import numpy as np
from output import add_save_argument, results_dir
from rdmp_gym.agents.protocol import TRAIN_SEED_LIMIT, final_test_seeds, interval, validation_seeds
from rdmp_gym.agents.training import environment_record
from rdmp_gym.envs.blackbox import MujocoJoints, make_blackbox

ROOT = Path(__file__).resolve().parent.parent
SOURCE = "Raffin et al. 2024, An Open-Loop Baseline for Reinforcement Learning Locomotion Tasks, arXiv 2310.05808"


@dataclass(frozen=True)
class EnvSetting:
    """The oscillator's fixed part on one env: PD gains, the swing/stance split and the frequency box (Hz)."""

    kp: float
    kd: float
    split: bool
    frequency: tuple[float, float]


#: per env: the authors' PD gains (their minimal scripts), the split as in their HalfCheetah script, the frequencies
ENVS: dict[str, EnvSetting] = {
    "Swimmer-v5": EnvSetting(kp=10.0, kd=0.5, split=False, frequency=(0.2, 1.5)),
    "HalfCheetah-v5": EnvSetting(kp=1.0, kd=0.05, split=True, frequency=(0.5, 5.0)),
}

#: the authors' published Swimmer oscillator (the code on their RLC 2024 slides)
PUBLISHED_SWIMMER = {"frequency": 0.62, "phases": (0.0, 0.95 * 2.0 * np.pi), "amplitude": 1.0, "kp": 10.0, "kd": 0.5}
#: other patterns of the wrapper beside its default, by env: (label, settings)
ALTERNATIVES: dict[str, tuple[tuple[str, dict[str, Any]], ...]] = {
    "Swimmer-v5": (("a start of one period", {"start_periods": 1.0}),
                   ("amplitude 0.5 and a start of one period", {"amplitude": 0.5, "start_periods": 1.0})),
    "HalfCheetah-v5": (("a wave about the reset posture (3 Hz, joint j at phase j pi / 3, 0.5 rad, PD 1 / 0.02)",
                        {"period": 1.0 / 3.0, "phases": -np.pi / 3.0, "amplitude": 0.5, "d_gains": 0.02,
                         "posture": (0.0,) * 6}),),
}
BUDGET = 100_000
POPSIZE = 10
SIGMA0 = 0.5
EVAL_EPISODES = 3
TEST_EPISODES = 10
REFERENCE_SEEDS = tuple(range(10))


@dataclass(frozen=True)
class OscillatorParams:
    """One oscillator per joint: ``amplitude``, ``phase`` (rad), ``offset`` ``[d]`` and the frequencies (Hz)."""

    amplitude: np.ndarray
    phase: np.ndarray
    offset: np.ndarray
    f_swing: float
    f_stance: float

    def to_dict(self) -> dict[str, Any]:
        return {"amplitude": self.amplitude.tolist(), "phase": self.phase.tolist(), "offset": self.offset.tolist(),
                "f_swing": self.f_swing, "f_stance": self.f_stance}

    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> OscillatorParams:
        """The parameters of :meth:`to_dict`'s record."""
        return cls(*(np.asarray(values[key], dtype=np.float64) for key in ("amplitude", "phase", "offset")),
                   float(values["f_swing"]), float(values["f_stance"]))


class OscillatorSpace:
    """The unit box ``x in [-1, 1]^n`` of CMA-ES and the oscillator it decodes to.

    ``x = [amplitude [d], phase [d], offset [d], f]`` (``f_swing, f_stance`` with ``split``): the amplitude in
    ``[0, r_j / 2]``, the phase in ``[0, 2 pi]``, the offset in ``c_j +- r_j / 4`` (``r_j``, ``c_j``: joint j's
    range and its centre) and the frequencies in ``frequency`` (Hz), each linear in ``x``.
    """

    def __init__(self, joint_range: np.ndarray, joint_centre: np.ndarray, frequency: tuple[float, float],
                 split: bool) -> None:
        self.joint_range = np.asarray(joint_range, dtype=np.float64)
        self.joint_centre = np.asarray(joint_centre, dtype=np.float64)
        if self.joint_range.ndim != 1 or self.joint_range.shape != self.joint_centre.shape \
                or np.any(self.joint_range <= 0):
            raise ValueError(f"joint_range: expected [d] ranges > 0 beside [d] centres, got {joint_range!r}")
        low, high = (float(value) for value in frequency)
        if not 0.0 < low < high:
            raise ValueError(f"frequency: expected (low, high) Hz with 0 < low < high, got {frequency!r}")
        self.frequency, self.split = (low, high), bool(split)
        self.n_joints = int(self.joint_range.size)
        self.size = 3 * self.n_joints + (2 if split else 1)

    def decode(self, x: np.ndarray) -> OscillatorParams:
        """The oscillator of ``x [n]`` (clipped to the unit box)."""
        x = np.clip(np.asarray(x, dtype=np.float64), -1.0, 1.0)
        if x.shape != (self.size,):
            raise ValueError(f"x: expected shape ({self.size},), got {x.shape}")
        unit = (x + 1.0) / 2.0
        d = self.n_joints
        low, high = self.frequency
        frequencies = low + (high - low) * unit[3 * d:]
        return OscillatorParams(amplitude=unit[:d] * self.joint_range / 2.0, phase=2.0 * np.pi * unit[d:2 * d],
                                offset=self.joint_centre + x[2 * d:3 * d] * self.joint_range / 4.0,
                                f_swing=float(frequencies[0]), f_stance=float(frequencies[-1]))


class Oscillator:
    """The open-loop policy: the oscillators of ``params`` tracked by a PD onto torques in ``[low, high]``."""

    def __init__(self, params: OscillatorParams, kp: float, kd: float, low: np.ndarray, high: np.ndarray) -> None:
        self.params, self.kp, self.kd = params, float(kp), float(kd)
        self.low, self.high = np.asarray(low, dtype=np.float64), np.asarray(high, dtype=np.float64)
        self.theta = np.zeros_like(params.amplitude)

    def reset(self) -> None:
        """Every oscillator's phase back to 0 (the episode's start)."""
        self.theta = np.zeros_like(self.params.amplitude)

    def desired(self) -> np.ndarray:
        """``[d]`` the desired joint positions now."""
        p = self.params
        return p.amplitude * np.sin(self.theta + p.phase) + p.offset

    def __call__(self, q: np.ndarray, qd: np.ndarray, dt: float) -> np.ndarray:
        """``[d]`` the torques for the joint state ``(q [d], qd [d])``; the phases then advance by ``dt`` (s)."""
        p = self.params
        torque = np.clip(self.kp * (self.desired() - q) - self.kd * qd, self.low, self.high)
        swing = np.sin(self.theta + p.phase) > 0.0
        self.theta = self.theta + 2.0 * np.pi * np.where(swing, p.f_swing, p.f_stance) * dt
        return torque


def env_space(env: gym.Env, setting: EnvSetting) -> tuple[OscillatorSpace, MujocoJoints]:
    """The parameter box of ``env``'s actuated joints (limited joints: their range; others: 2 pi about 0)."""
    joints = MujocoJoints(env)
    model = env.unwrapped.model
    limited = np.asarray(model.jnt_limited[joints.joint_ids], dtype=bool)
    low, high = model.jnt_range[joints.joint_ids, 0], model.jnt_range[joints.joint_ids, 1]
    joint_range = np.where(limited, high - low, 2.0 * np.pi)
    centre = np.where(limited, (low + high) / 2.0, 0.0)
    return OscillatorSpace(joint_range, centre, setting.frequency, setting.split), joints


def episode(env: gym.Env, joints: MujocoJoints, policy: Oscillator, seed: int) -> tuple[float, int]:
    """One episode of ``policy`` from ``env.reset(seed)``: (return, env steps)."""
    env.reset(seed=int(seed))
    policy.reset()
    dt = float(env.unwrapped.dt)
    total, steps = 0.0, 0
    while True:
        q, qd = joints(env)
        _, reward, terminated, truncated, _ = env.step(policy(q, qd, dt).astype(env.action_space.dtype))
        total, steps = total + float(reward), steps + 1
        if terminated or truncated:
            return total, steps


def mean_return(env: gym.Env, joints: MujocoJoints, policy: Oscillator, seeds: Sequence[int]) -> float:
    """The mean return of ``policy`` over one episode per reset seed."""
    return float(np.mean([episode(env, joints, policy, seed)[0] for seed in seeds]))


def cma_search(env: gym.Env, setting: EnvSetting, seed: int, budget: int = BUDGET, popsize: int = POPSIZE,
               eval_seeds: Sequence[int] = (), test_seeds: Sequence[int] = ()) -> dict[str, Any]:
    """CMA-ES on the oscillator of ``env``: generations of ``popsize`` episodes, each from a training reset seed drawn
    from ``seed``, until ``budget`` env steps are spent (the last generation is whole, so it may end past it).

    Returns:
        ``returns`` (every training episode's, in order) and their ``train_seeds``, ``best_so_far`` (the running
        maximum of the returns), ``best`` and ``best_params``, ``curve`` (after each generation: env steps, best so
        far, the mean's return on ``eval_seeds``), ``final`` (the mean's return on ``test_seeds``) and
        ``final_params``, the seconds of the training (``train_wall_s``, ``train_cpu_s``) and of the evaluations
        (``eval_wall_s``).
    """
    if isinstance(budget, bool) or not isinstance(budget, (int, np.integer)) or budget < 1:
        raise ValueError(f"budget: expected a whole number of env steps >= 1, got {budget!r}")
    space, joints = env_space(env, setting)
    low, high = env.action_space.low, env.action_space.high

    def make(x: np.ndarray) -> Oscillator:
        return Oscillator(space.decode(x), setting.kp, setting.kd, low, high)

    rng = np.random.default_rng(seed)
    strategy = cma.CMAEvolutionStrategy(np.zeros(space.size), SIGMA0, {
        "popsize": popsize, "bounds": [-1.0, 1.0], "seed": seed + 1, "verbose": -9})
    returns: list[float] = []
    train_seeds: list[int] = []
    best_so_far: list[float] = []
    curve: list[dict[str, Any]] = []
    best, best_x = -np.inf, np.zeros(space.size)
    steps, train_wall, train_cpu, eval_wall = 0, 0.0, 0.0, 0.0
    while steps < budget:
        wall, cpu = time.perf_counter(), time.process_time()
        candidates = strategy.ask()
        fitness = []
        for x in candidates:
            train_seeds.append(int(rng.integers(TRAIN_SEED_LIMIT)))
            total, used = episode(env, joints, make(x), train_seeds[-1])
            steps += used
            returns.append(total)
            fitness.append(-total)
            if total > best:
                best, best_x = total, np.asarray(x, dtype=np.float64).copy()
            best_so_far.append(best)
        strategy.tell(candidates, fitness)
        train_wall += time.perf_counter() - wall
        train_cpu += time.process_time() - cpu
        wall = time.perf_counter()
        mark = {"env_steps": steps, "best_so_far": best}
        if eval_seeds:
            mark["mean_return"] = mean_return(env, joints, make(strategy.mean), eval_seeds)
        curve.append(mark)
        eval_wall += time.perf_counter() - wall
    wall = time.perf_counter()
    final = mean_return(env, joints, make(strategy.mean), test_seeds) if test_seeds else None
    eval_wall += time.perf_counter() - wall
    return {"returns": returns, "train_seeds": train_seeds, "best_so_far": best_so_far, "best": float(best),
            "best_params": space.decode(best_x).to_dict(), "curve": curve, "final": final,
            "final_params": space.decode(strategy.mean).to_dict(), "env_steps": steps, "n_params": space.size,
            "train_wall_s": train_wall, "train_cpu_s": train_cpu, "eval_wall_s": eval_wall}


# ------------------------------------------------------------------ the reference rows
def published_swimmer(seeds: Sequence[int]) -> list[float]:
    """The authors' published Swimmer oscillator on Swimmer-v5, one episode per reset seed: the returns."""
    env = gym.make("Swimmer-v5")
    _, joints = env_space(env, ENVS["Swimmer-v5"])
    p = PUBLISHED_SWIMMER
    params = OscillatorParams(np.full(2, p["amplitude"]), np.asarray(p["phases"]), np.zeros(2), p["frequency"],
                              p["frequency"])
    policy = Oscillator(params, p["kp"], p["kd"], env.action_space.low, env.action_space.high)
    returns = [episode(env, joints, policy, seed)[0] for seed in seeds]
    env.close()
    return returns


def wrapper_default(env_id: str, seeds: Sequence[int], **settings: Any) -> list[float]:
    """``make_blackbox(env_id, **settings)`` under action 0, one episode per reset seed: the returns."""
    env = make_blackbox(env_id, **settings)
    returns = []
    for seed in seeds:
        env.reset(seed=int(seed))
        returns.append(float(env.step(np.zeros(env.action_space.shape, np.float32))[1]))
    env.close()
    return returns


def zero_action(env_id: str, seeds: Sequence[int]) -> list[float]:
    """The raw env under its action 0 at every step, one episode per reset seed: the returns."""
    env = gym.make(env_id)
    returns = []
    for seed in seeds:
        env.reset(seed=int(seed))
        total, done = 0.0, False
        while not done:
            _, reward, terminated, truncated, _ = env.step(np.zeros(env.action_space.shape, env.action_space.dtype))
            total, done = total + float(reward), terminated or truncated
        returns.append(total)
    env.close()
    return returns


def reference_rows(env_ids: Sequence[str], seeds: Sequence[int] = REFERENCE_SEEDS) -> list[dict[str, Any]]:
    """The published oscillator (Swimmer) and the wrapper's default pattern beside the zero action, per env."""
    rows = []
    for env_id in env_ids:
        cases: list[tuple[str, Any]] = []
        if env_id == "Swimmer-v5":
            cases.append(("published oscillator (the authors' Swimmer parameters)", lambda: published_swimmer(seeds)))
        cases.append(("make_blackbox default pattern, a = 0", lambda e=env_id: wrapper_default(e, seeds)))
        for label, settings in ALTERNATIVES.get(env_id, ()):
            cases.append((f"make_blackbox, {label}, a = 0",
                          lambda e=env_id, s=settings: wrapper_default(e, seeds, **s)))
        cases.append(("raw zero action", lambda e=env_id: zero_action(e, seeds)))
        for label, run in cases:
            returns = run()
            rows.append({"env": env_id, "method": label, "seeds": list(seeds), "returns": returns,
                         "mean": float(np.mean(returns)), "std": float(np.std(returns))})
    return rows


# ------------------------------------------------------------------ runs and summary
def env_setting(env_id: str, split: str) -> EnvSetting:
    """The env's setting of :data:`ENVS`, its swing/stance split as ``split`` says (``env``: as in ENVS)."""
    setting = ENVS[env_id]
    if split == "env":
        return setting
    if split not in ("on", "off"):
        raise ValueError(f"split: expected 'env', 'on' or 'off', got {split!r}")
    return EnvSetting(setting.kp, setting.kd, split == "on", setting.frequency)


def run_settings(env_id: str, budget: int, popsize: int, split: str) -> dict[str, Any]:
    setting = env_setting(env_id, split)
    return {"env": env_id, "budget": budget, "popsize": popsize, "sigma0": SIGMA0, "kp": setting.kp,
            "kd": setting.kd, "split": setting.split, "frequency": list(setting.frequency),
            "eval_episodes": EVAL_EPISODES, "test_episodes": TEST_EPISODES}


def seed_path(root: Path, env_id: str, split: bool, seed: int) -> Path:
    """Where the run of (env, split, seed) lives under ``root``."""
    return root / env_id / ("swing-stance" if split else "one-frequency") / f"seed_{seed}.json"


def best_test_return(env_id: str, setting: EnvSetting, best_params: dict[str, Any]) -> float:
    """The mean return of the best training candidate (``best_params``, a :meth:`OscillatorParams.to_dict` record)
    on the test contexts."""
    env = gym.make(env_id)
    _, joints = env_space(env, setting)
    policy = Oscillator(OscillatorParams.from_dict(best_params), setting.kp, setting.kd, env.action_space.low,
                        env.action_space.high)
    value = mean_return(env, joints, policy, final_test_seeds(TEST_EPISODES).tolist())
    env.close()
    return value


def run_seed(env_id: str, seed: int, root: Path, budget: int, popsize: int, split: str = "env") -> dict[str, Any]:
    """The run of (env, seed): loaded if finished under ``root`` with the same settings, else trained and saved;
    the best training candidate's test return (``best_test``) is added to the seed's JSON where it is missing."""
    setting = env_setting(env_id, split)
    path = seed_path(root, env_id, setting.split, seed)
    settings = run_settings(env_id, budget, popsize, split)
    if path.exists():
        document = json.loads(path.read_text())
        if document["settings"] != settings:
            raise ValueError(f"--run-dir: {path} was run with other settings ({document['settings']}); pass another "
                             f"--run-dir")
    else:
        env = gym.make(env_id)
        result = cma_search(env, setting, seed, budget, popsize, validation_seeds(EVAL_EPISODES).tolist(),
                            final_test_seeds(TEST_EPISODES).tolist())
        env.close()
        document = {"settings": settings, "seed": seed, **result}
    if "best_test" not in document:
        document["best_test"] = best_test_return(env_id, setting, document["best_params"])
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(document, indent=1) + "\n")
    return document


def summarise(env_id: str, runs: list[dict[str, Any]]) -> dict[str, Any]:
    """IQM [95 % CI] over seeds of the final and best returns, the curve, the training seconds per seed."""
    finals = np.array([r["final"] for r in runs])
    bests = np.array([r["best"] for r in runs])
    best_tests = np.array([r["best_test"] for r in runs])
    marks = [m["env_steps"] for m in runs[0]["curve"]]
    curve = []
    for index, steps in enumerate(marks):
        values = [r["curve"][index] for r in runs if len(r["curve"]) > index]
        curve.append({"env_steps": steps, "mean_return": interval([v["mean_return"] for v in values]).to_dict(),
                      "best_so_far": interval([v["best_so_far"] for v in values]).to_dict()})
    return {"env": env_id, "split": runs[0]["settings"]["split"], "seeds": [r["seed"] for r in runs],
            "n_params": runs[0]["n_params"],
            "env_steps": int(np.median([r["env_steps"] for r in runs])), "final": interval(finals).to_dict(),
            "best": interval(bests).to_dict(), "best_test": interval(best_tests).to_dict(),
            "final_per_seed": finals.tolist(), "best_per_seed": bests.tolist(),
            "best_test_per_seed": best_tests.tolist(), "best_params_per_seed": [r["best_params"] for r in runs],
            "train_wall_s_per_seed": [round(r["train_wall_s"], 2) for r in runs],
            "train_cpu_s_per_seed": [round(r["train_cpu_s"], 2) for r in runs], "curve": curve,
            "settings": runs[0]["settings"]}


def _cell(value: dict[str, float]) -> str:
    return f"{value['estimate']:.1f} [{value['low']:.1f}, {value['high']:.1f}]"


def table(rows: list[dict[str, Any]], references: list[dict[str, Any]]) -> str:
    """Markdown: per env the IQM [95 % CI] over seeds of the returns (CMA-ES's final mean and the best training
    candidate on the test contexts, the best training episode), the env steps and the seconds per seed."""
    lines = ["| env | swing/stance split | parameters | env steps | final mean, test | best candidate, test | "
             "best training episode | seconds per seed (wall / CPU, median) | seeds |",
             "|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        split = "yes" if row["split"] else "no"
        lines.append(f"| {row['env']} | {split} | {row['n_params']} | {row['env_steps']} | {_cell(row['final'])} | "
                     f"{_cell(row['best_test'])} | {_cell(row['best'])} | "
                     f"{np.median(row['train_wall_s_per_seed']):.1f} / {np.median(row['train_cpu_s_per_seed']):.1f} "
                     f"| {len(row['seeds'])} |")
    lines.insert(0, "IQM over seeds [95% bootstrap CI]; returns of 1000-step episodes")
    lines += ["", "| env | reference (reset seeds 0-9, 1000 steps) | mean return | std |", "|---|---|---|---|"]
    lines += [f"| {r['env']} | {r['method']} | {r['mean']:.2f} | {r['std']:.2f} |" for r in references]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--envs", nargs="+", default=list(ENVS), choices=list(ENVS))
    parser.add_argument("--seeds", nargs="+", type=int, default=list(range(10)))
    parser.add_argument("--budget", type=int, default=BUDGET, help="env steps per run")
    parser.add_argument("--popsize", type=int, default=POPSIZE, help="CMA-ES's population (episodes per generation)")
    parser.add_argument("--split", nargs="+", default=["env"], choices=("env", "on", "off"),
                        help="the swing/stance split: as each env's setting (Swimmer off, HalfCheetah on), on, or off; "
                             "several: one row each (a setting repeated on an env runs once)")
    parser.add_argument("--run-dir", default=str(ROOT / "runs" / "open_loop_oscillator"), help="one JSON per seed")
    parser.add_argument("--summary-only", action="store_true", help="summarise the finished seeds; train nothing")
    add_save_argument(parser)
    args = parser.parse_args(argv)
    root = Path(args.run_dir)
    rows = []
    for env_id in args.envs:
        splits = {env_setting(env_id, split).split: split for split in reversed(args.split)}
        for split in sorted(splits.values(), key=args.split.index):
            runs = []
            for seed in args.seeds:
                path = seed_path(root, env_id, env_setting(env_id, split).split, seed)
                if args.summary_only and not path.exists():
                    continue
                runs.append(run_seed(env_id, seed, root, args.budget, args.popsize, split))
                run = runs[-1]
                print(f"{env_id} (split {run['settings']['split']}) seed {seed}: best {run['best']:.1f}, final "
                      f"{run['final']:.1f}, {run['train_wall_s']:.1f} s", flush=True)
            if runs:
                rows.append(summarise(env_id, runs))
    references = reference_rows(args.envs)
    print(table(rows, references))
    command = "python benchmarks/bench_open_loop_oscillator.py" + (f" --split {' '.join(args.split)}"
                                                                   if args.split != ["env"] else "")
    document = {"command": command + (" --save" if args.save else ""),
                "source": SOURCE, "rows": rows, "references": references, "environment": environment_record(),
                "cpus": os.cpu_count()}
    target = results_dir(args.save) / "open_loop_oscillator.json"
    target.write_text(json.dumps(document, indent=1) + "\n")
    print(f"wrote {target}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
