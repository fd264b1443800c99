"""How smooth a cycle's change is where it takes over: acceleration and jerk across the hand-over, planned and executed.

For each task's cycle-level face, each change size and each context, one episode runs the imitation and one changes
the parameters at the start of cycle 2 by ``size`` times a random unit-variance direction. Measured within the
hand-over window (the cycle's start to half a period after it), against what the paths have of their own:

- ``jerk_ratio_planned``: the planned tool path's peak jerk (its third difference) over the larger of the peaks of
  the two parameters' own rollouts over the whole episode (1: no rougher than either);
- ``accel_step_planned``: the largest step-to-step change of the planned acceleration at the switch (m/s² per step)
  over that of the unchanged rollout anywhere (C2: a jump would show as a spike);
- ``jerk_ratio_executed``: the same peak jerk of the simulated tool tip (every control step) over the unchanged
  episode's executed peak;
- ``joint_accel_ratio``: the servo targets' peak joint acceleration in the window over the unchanged episode's peak;
- ``episode_jerk_ratio``: the task's smoothness measure of the whole executed path over the imitation's;
- ``zero_change_exact``: the zero change reproduces the unchanged episode bit for bit (return and cost trace).

    python benchmarks/bench_handover.py --out benchmarks/results/handover.json --figure docs/figures/handover.png
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import gymnasium as gym
import numpy as np
import rdmp_gym.envs  # noqa: F401  (registers the ids)
from output import add_save_argument, results_dir
from rdmp_gym.agents.cycle_training import executed_jerk_ratio

ENVS = ("rdmp_gym/PandaWipeCycle-v3", "rdmp_gym/ArmarWipeCycle-v3", "rdmp_gym/PandaDrumCycle-v1",
        "rdmp_gym/ArmarDrumCycle-v1")
SIZES = (0.02, 0.05, 0.1, 0.2)
CYCLE = 2
#: the committed figure (``--save``)
FIGURE = Path(__file__).resolve().parent.parent / "docs" / "assets" / "handover.png"


def _episode(env, change: np.ndarray | None, seed: int) -> dict:
    """One episode with ``change`` from cycle :data:`CYCLE` on (None: the imitation); what the measures need."""
    env.reset(seed=seed)
    zero = np.zeros(env.action_space.shape)
    for cycle in range(env.n_cycles):
        _, reward, terminated, _, info = env.step(zero if change is None or cycle < CYCLE else change)
        if terminated:
            break
    face = env.face
    tip = None if face.tool_path is None else face.tool_path.tip[: face.tool_path.steps]
    return {"reward": reward, "trace": info["cost_trace"], "path": face.solution.plan.path.copy(),
            "targets": face.live_targets.q.copy(), "tip": tip, "episode_jerk": executed_jerk_ratio(env),
            "refused": info["refused"]}


def _third(path: np.ndarray, dt: float) -> np.ndarray:
    return np.abs(np.diff(path, n=3, axis=0)).max(axis=-1) / dt**3


def _measure(env, size: float, seed: int) -> dict:
    face, dt = env.face, env.face.dt
    rng = np.random.default_rng(seed)
    change = np.clip(size * rng.standard_normal(env.action_space.shape), -1.0, 1.0)
    base, changed = _episode(env, None, seed), _episode(env, change, seed)
    again = _episode(env, np.zeros(env.action_space.shape), seed)
    own_after = face.plan(*face._split(change)).path
    step = int(env.start_steps[CYCLE])
    window = slice(step - 3, step + round(env.handover / dt) + 3)
    own = max(_third(base["path"], dt).max(), _third(own_after, dt).max())
    accel = np.diff(changed["path"], n=2, axis=0) / dt**2
    base_accel = np.diff(base["path"], n=2, axis=0) / dt**2
    joint_accel = np.abs(np.diff(changed["targets"], n=2, axis=0)).max(axis=1) / dt**2
    base_joint = np.abs(np.diff(base["targets"], n=2, axis=0)).max(axis=1) / dt**2
    executed = (float(_third(changed["tip"], dt)[window].max() / _third(base["tip"], dt).max())
                if changed["tip"] is not None and base["tip"] is not None else float("nan"))
    return {"size": size, "seed": seed, "refused": len(changed["refused"]),
            "jerk_ratio_planned": float(_third(changed["path"], dt)[window].max() / own),
            "accel_step_planned": float(np.abs(np.diff(accel[window], axis=0)).max()
                                        / np.abs(np.diff(base_accel, axis=0)).max()),
            "jerk_ratio_executed": executed,
            "joint_accel_ratio": float(joint_accel[window].max() / base_joint.max()),
            "episode_jerk_ratio": changed["episode_jerk"],
            "zero_change_exact": bool(again["reward"] == base["reward"]
                                      and np.array_equal(again["trace"], base["trace"]))}


def _figure(env_id: str, out: Path) -> None:
    """A path coordinate, its acceleration and its jerk across a hand-over (imitation, the changed parameters' own
    rollout, the executed blend)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    env = gym.make(env_id).unwrapped
    face, dt = env.face, env.face.dt
    change = np.clip(0.1 * np.random.default_rng(0).standard_normal(env.action_space.shape), -1.0, 1.0)
    base, changed = _episode(env, None, 0), _episode(env, change, 0)
    own = face.plan(*face._split(change)).path
    step, width = int(env.start_steps[CYCLE]), round(env.handover / dt)
    span = slice(step - width, step + 3 * width)
    t = face.times[span]
    figure, axes = plt.subplots(3, 1, figsize=(7, 6.5), sharex=True)
    for label, path, style in (("imitation", base["path"], ":"), ("changed parameters' own rollout", own, "--"),
                               ("executed (hand-over)", changed["path"], "-")):  # the planned tool paths
        axes[0].plot(t, path[span, 0], style, label=label)
        axes[1].plot(t[1:-1], (np.diff(path, n=2, axis=0) / dt**2)[span.start:span.stop - 2, 0], style)
        axes[2].plot(t[2:-1], (np.diff(path, n=3, axis=0) / dt**3)[span.start:span.stop - 3, 0], style)
    for axis, label in zip(axes, ("x (m)", "acceleration x (m/s²)", "jerk x (m/s³)"), strict=True):
        axis.axvspan(env.starts[CYCLE], env.starts[CYCLE] + env.handover, color="0.9")
        axis.set_ylabel(label)
    axes[0].legend(fontsize=8)
    axes[2].set_xlabel("time (s); shaded: the hand-over of cycle 2's change")
    axes[0].set_title(f"{env_id.split('/')[-1]}: a change of 0.1 per action dimension at cycle 2", fontsize=10)
    figure.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(out, dpi=110)
    env.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3)
    add_save_argument(parser)
    args = parser.parse_args()
    table = {}
    for env_id in ENVS:
        env = gym.make(env_id).unwrapped
        rows = [_measure(env, size, seed) for size in SIZES for seed in range(args.seeds)]
        env.close()
        table[env_id] = rows
        print(env_id)
        print("  size  planned jerk  accel step  executed jerk  joint accel  episode jerk  exact")
        for size in SIZES:
            mine = [r for r in rows if r["size"] == size]
            print(f"  {size:4.2f}  " + "  ".join(f"{np.nanmax([r[key] for r in mine]):11.2f}" for key in (
                "jerk_ratio_planned", "accel_step_planned", "jerk_ratio_executed", "joint_accel_ratio",
                "episode_jerk_ratio")) + f"  {all(r['zero_change_exact'] for r in mine)}")
    (results_dir(args.save) / "handover.json").write_text(json.dumps({"sizes": SIZES, "cycle": CYCLE, "rows": table},
                                                                      indent=1))
    _figure(ENVS[0], FIGURE if args.save else results_dir(False) / "handover.png")


if __name__ == "__main__":
    main()
