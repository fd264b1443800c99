"""Can the learners' actions lift the approach over the cup? ``rdmp_gym/ArmarWipe-v1``, cup contexts.

For the first ``--contexts`` cup contexts among the test and validation seeds of the agents' protocol:

1. the imitation (``a = 0``): does it touch / move the cup;
2. the largest lift over the cup that a box corner reaches: the commanded path's height is (nearly)
   linear in the action, so ``a = sign(∂z/∂a)`` averaged over the steps where the sponge is within
   9.5 cm (cup radius + sponge half length) of the cup, for the transient weights alone and for all
   groups; each is run as an episode (touch, shift, coverage, success, jerk, peak joint acceleration);
3. what the learners' smooth exploration reaches: the same linearised lift for 2000 samples
   ``squash(0.3 · ε)``, ``ε`` from :class:`~rdmp_gym.agents.learners.smooth_exploration.SmoothNoise` (length 5),
   i.e. the contextual learners' first batch around the imitation;
4. how much lift is needed: the imitation's path raised by ``h`` around the cup (a hand-made path,
   ``run_path``), for h = 1, 2, 3, 4, 6 cm.

    python benchmarks/bench_cup_reach.py [--contexts 6] [--save]
"""

from __future__ import annotations

import argparse
import json
import os

os.environ.setdefault("MUJOCO_GL", "egl")

import gymnasium as gym
import numpy as np
import rdmp_gym.envs  # noqa: F401  (registers the env)
from output import add_save_argument, results_dir
from rdmp_gym.agents.learners.smooth_exploration import SmoothNoise, block_layout, squash
from rdmp_gym.agents.protocol import final_test_seeds, validation_seeds

NEAR = 0.035 + 0.06          # cup radius + about half the sponge's length (m)
LIFTS = (0.01, 0.02, 0.03, 0.04, 0.06)


def _episode(env: gym.Env, action: np.ndarray, seed: int) -> dict:
    env.reset(seed=seed)
    _, reward, _, _, info = env.step(action.astype(np.float32))
    return {"return": float(reward), "touch_steps": int(info["obstacle_touch_steps"]),
            "shift_mm": 1000 * float(info["obstacle_shift"]), "coverage": float(info["coverage"]),
            "success": bool(info["is_success"]), "valid": bool(info["valid"]),
            "jerk_ratio": float(info["jerk_ratio"]), "peak_joint_accel": float(info["peak_joint_accel"])}


def _context(env: gym.Env, seed: int, samples: np.ndarray) -> dict:
    base = env.unwrapped
    n = env.action_space.shape[0]
    cup = env.reset(seed=seed)[0][11:13].astype(np.float64)

    def height(action: np.ndarray) -> np.ndarray:
        return base.rollout_path(base.action_to_params(action))[:, 2]

    path = base.rollout_path(base.action_to_params(np.zeros(n)))
    window = np.flatnonzero(np.linalg.norm(path[:, :2] - cup, axis=1) < NEAR)
    if window.size == 0:
        window = np.array([int(np.argmin(np.linalg.norm(path[:, :2] - cup, axis=1)))])
    gradient = np.stack([height(e)[window] - path[window, 2] for e in np.eye(n)], axis=1).mean(axis=0)   # [n]
    transient = np.zeros(n)
    for name, part in base.param_slices().items():
        if name.startswith("transient"):
            transient[part] = np.sign(gradient[part])
    result = {"seed": seed, "cup": cup.tolist(), "imitation": _episode(env, np.zeros(n), seed)}
    for name, action in (("transient_corner", transient), ("all_groups_corner", np.sign(gradient))):
        lift = height(action)[window] - path[window, 2]
        result[name] = {"lift_cm": [100 * float(lift.min()), 100 * float(lift.max())], **_episode(env, action, seed)}
    reached = 100 * (samples @ gradient)
    result["exploration_lift_cm"] = {"median": float(np.median(reached)), "p99": float(np.percentile(reached, 99)),
                                     "max": float(reached.max())}
    fade = np.zeros(len(path))
    fade[max(window[0] - 10, 0):window[-1] + 11] = 1.0
    fade = np.convolve(fade, np.ones(11) / 11, mode="same")
    result["hand_lift"] = {}
    for h in LIFTS:
        env.reset(seed=seed)
        raised = path.copy()
        raised[:, 2] += h * fade
        info = base.run_path(raised)[1]
        result["hand_lift"][f"{100 * h:.0f}cm"] = {"touch_steps": int(info["obstacle_touch_steps"]),
                                                   "shift_mm": 1000 * float(info["obstacle_shift"])}
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--contexts", type=int, default=6, help="cup contexts")
    add_save_argument(parser)
    args = parser.parse_args()
    env = gym.make("rdmp_gym/ArmarWipe-v1", disable_env_checker=True)
    base = env.unwrapped
    n = env.action_space.shape[0]
    noise = SmoothNoise(n, block_layout(base.param_slices(), base.dmp.n_dims), 5.0)
    samples = squash(0.3 * noise.sample(np.ones(noise.n_blocks), 2000, np.random.default_rng(0)))
    seeds = [int(s) for s in np.concatenate([final_test_seeds(20), validation_seeds(10)])]
    cups = [s for s in seeds if env.reset(seed=s)[0][10] > 0.5][:args.contexts]
    rows = [_context(env, s, samples) for s in cups]
    print(f"{'seed':>11} {'imitation':>16} {'transient corner':>30} {'all-groups corner':>40} "
          f"{'exploration p99/max':>20} {'hand lift needed':>16}")
    for r in rows:
        imitation = f"{r['imitation']['touch_steps']} st {r['imitation']['shift_mm']:.0f} mm"
        corners = []
        for key in ("transient_corner", "all_groups_corner"):
            c = r[key]
            extra = f" cov {c['coverage']:.2f} qdd {c['peak_joint_accel']:.0f}" if key == "all_groups_corner" else ""
            corners.append(f"+{c['lift_cm'][0]:.1f}-{c['lift_cm'][1]:.1f} cm: {c['touch_steps']} st "
                           f"{c['shift_mm']:.0f} mm{extra}")
        needed = next((k for k, v in r["hand_lift"].items() if v["touch_steps"] == 0), "> 6cm")
        explore = f"{r['exploration_lift_cm']['p99']:.1f}/{r['exploration_lift_cm']['max']:.1f} cm"
        print(f"{r['seed']:>11} {imitation:>16} {corners[0]:>30} {corners[1]:>40} {explore:>20} {needed:>16}")
    out = results_dir(args.save) / "cup_reach.json"
    out.write_text(json.dumps({"contexts": rows, "exploration": {"sigma": 0.3, "length": 5.0, "samples": 2000}},
                              indent=1) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
