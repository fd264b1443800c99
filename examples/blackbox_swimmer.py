"""A rhythmic DMP on Gymnasium's Swimmer-v5 through the black-box wrapper, refined by CMA-ES (ask/tell).

One ``step`` of the wrapped env is one whole 40 s episode: the action is the DMP's parameters (the cycle's shape
per joint, its amplitude and the posture it is centred on), a PD controller tracks the DMP on Swimmer's torques.

    python examples/blackbox_swimmer.py                  # about 10 s: the initial DMP, random actions, 6 updates
    python examples/blackbox_swimmer.py --updates 20
"""

import argparse

import numpy as np
from rdmp_gym.agents.learners import EpisodeBatch, make_learner
from rdmp_gym.agents.tasks import run_episode
from rdmp_gym.envs.blackbox import make_blackbox

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--updates", type=int, default=6, help="CMA-ES updates (8 episodes each)")
parser.add_argument("--seed", type=int, default=0)
args = parser.parse_args()

# Swimmer's entry in ENV_DEFAULTS: PD gains 10 / 0.5, period 1 / 0.62 s, phases 0 and 0.95 x 2 pi, 1 rad, a start
# of 0.1 period
env = make_blackbox("Swimmer-v5")
n = env.action_space.shape[0]
print(f"{n} action dimensions: " + ", ".join(f"{k} {s.stop - s.start}" for k, s in env.param_map.slices.items()))

context, _ = env.reset(seed=args.seed)
_, initial, _, _, info = env.step(np.zeros(n, np.float32))
print(f"initial DMP (a = 0): return {initial:.1f}, tracking RMS {info['tracking_rmse']:.3f} rad, "
      f"{info['env_steps']} env steps")
rng = np.random.default_rng(args.seed)
random = [run_episode(env, rng.uniform(-1, 1, n), seed, None)["return"] for seed in range(8)]
print(f"uniform random actions: mean return {np.mean(random):.1f} (min {min(random):.1f}, max {max(random):.1f})")

learner = make_learner("cmaes", np.zeros(n), 8, np.random.default_rng(args.seed), {"sigma": 0.3})
for update in range(args.updates):
    actions = learner.ask()
    seeds = 1000 * (update + 1) + np.arange(8)
    results = [run_episode(env, a, int(s), None) for a, s in zip(actions, seeds, strict=True)]
    learner.tell(EpisodeBatch(actions=actions, returns=np.array([r["return"] for r in results]),
                              cost_traces=np.stack([r["cost_trace"] for r in results]),
                              valid=np.ones(8, bool), seeds=seeds))
    mean_policy = run_episode(env, learner.mean, args.seed, None)["return"]
    print(f"update {update + 1}: batch mean {np.mean([r['return'] for r in results]):.1f}, "
          f"policy mean {mean_policy:.1f}")
env.close()
