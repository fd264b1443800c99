"""What an episode costs against the bare physics it runs: the simulation core's overhead, for every robot.

For each env id and held-out context, one episode of the imitation (action 0) is run with the servo targets of
every control step recorded; then the same targets are replayed on a fresh copy of the scene with nothing but
``mj_step`` calls (one physics step at a time where the episode stepped finely, ``frame_skip`` at once
elsewhere). Times are the process's CPU time (``time.process_time``), the best of ``--repeats`` runs, so that other
processes on the machine do not count. Reported per env: the whole ``env.step`` (path, IK, simulation, reward),
the simulation core alone (:func:`~rdmp_gym.envs.tasks.wiping.simulation.simulate_wipe`, or for the rhythmic tasks
:meth:`~rdmp_gym.envs.servo.ServoSimulation.run`, which steps one physics step at a time to record every sensor at
500 Hz), the bare replay (``frame_skip`` steps at once where the core allows it), and the ratios.

    python benchmarks/bench_sim_cost.py --save          # writes benchmarks/results/sim_cost.json
"""

from __future__ import annotations

import argparse
import json
import os
import time

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import gymnasium as gym
import mujoco
import numpy as np
import rdmp_gym.envs  # registers the ids; the wiping task's module is patched below
import rdmp_gym.envs.servo as servo
import rdmp_gym.envs.tasks.wiping.simulation as wiping
from output import add_save_argument, results_dir


class _Recorder:
    """Wraps ``WipeSimulation.finish`` (the wiping hook's record of a control step) and ``simulate_wipe`` to record the
    servo targets and time the core."""

    def __init__(self) -> None:
        self.targets: list[np.ndarray] = []
        self.fine: list[bool] = []
        self.core_seconds = 0.0
        self._finish, self._simulate = wiping.WipeSimulation.finish, wiping.simulate_wipe

    def __enter__(self) -> _Recorder:
        recorder, finish, simulate = self, self._finish, self._simulate

        def recording_finish(sim: wiping.WipeSimulation, k: int) -> bool:
            fine = sim.first_contact >= 0 and k < sim.first_contact + sim.fine_window   # before this step's contact
            stop = finish(sim, k)
            recorder.targets.append(sim.scene.data.ctrl.copy())
            recorder.fine.append(fine)
            return stop

        def timed_simulate(*args, **kwargs):
            start = time.process_time()
            trace = simulate(*args, **kwargs)
            recorder.core_seconds += time.process_time() - start
            return trace

        wiping.WipeSimulation.finish = recording_finish
        rdmp_gym.envs.tasks.wiping.task.simulate_wipe = timed_simulate
        return self

    def __exit__(self, *exc: object) -> None:
        wiping.WipeSimulation.finish = self._finish
        rdmp_gym.envs.tasks.wiping.task.simulate_wipe = self._simulate


class _ServoRecorder:
    """Wraps ``ServoSimulation.step`` and ``run`` (the rhythmic tasks' core) to record the targets and time the core;
    the core steps the physics one step at a time to record every sensor at 500 Hz."""

    def __init__(self) -> None:
        self.targets: list[np.ndarray] = []
        self.fine: list[bool] = []
        self.core_seconds = 0.0
        self._step, self._run = servo.ServoSimulation.step, servo.ServoSimulation.run

    def __enter__(self) -> _ServoRecorder:
        recorder, step, run = self, self._step, self._run

        def recording_step(sim: servo.ServoSimulation, k: int, target: np.ndarray) -> bool:
            stop = step(sim, k, target)
            recorder.targets.append(sim.scene.data.ctrl.copy())
            recorder.fine.append(False)        # the bare replay steps frame_skip at once
            return stop

        def timed_run(sim: servo.ServoSimulation, *args, **kwargs) -> None:
            start = time.process_time()
            run(sim, *args, **kwargs)
            recorder.core_seconds += time.process_time() - start

        servo.ServoSimulation.step = recording_step
        servo.ServoSimulation.run = timed_run
        return self

    def __exit__(self, *exc: object) -> None:
        servo.ServoSimulation.step, servo.ServoSimulation.run = self._step, self._run


def _start_state(unwrapped: gym.Env, seed: int) -> None:
    """Reset ``unwrapped`` to context ``seed`` with the arm at rest where the imitation's episode starts."""
    unwrapped.reset(seed=seed)
    if not hasattr(unwrapped.task, "solve_path"):       # a task on the face's own IK: the face solves its plan
        plan = unwrapped.plan(unwrapped.action_map.theta0, np.zeros(len(unwrapped.extra_scales)))
        unwrapped.scene.set_arm_state(unwrapped.solve_plan(plan, plan.world()).q[0])
        return
    theta = unwrapped.action_to_params(np.zeros(unwrapped.action_space.shape))
    unwrapped.scene.set_arm_state(unwrapped.task.solve_path(unwrapped.rollout_path(theta), unwrapped.context).q[0])


def _replay(env: gym.Env, seed: int, targets: list[np.ndarray], fine: list[bool]) -> float:
    """CPU seconds of the bare ``mj_step`` calls of a recorded episode, from the same start state."""
    unwrapped = env.unwrapped
    _start_state(unwrapped, seed)
    scene = unwrapped.scene
    model, data, skip = scene.model, scene.data, unwrapped.frame_skip
    step = mujoco.mj_step
    start = time.process_time()
    for ctrl, one_by_one in zip(targets, fine, strict=True):
        data.ctrl[:] = ctrl
        if one_by_one:
            for _ in range(skip):
                step(model, data)
        else:
            step(model, data, skip)
    return time.process_time() - start


def measure(env_id: str, seeds: list[int], repeats: int) -> dict:
    """Best-of-``repeats`` CPU seconds per episode: env.step, the simulation core, the bare replay."""
    env = gym.make(env_id)
    recording = _Recorder if hasattr(env.unwrapped.task, "solve_path") else _ServoRecorder      # the wiping hook's
    rows = []
    for seed in seeds:
        best = {"episode": np.inf, "core": np.inf, "bare": np.inf}
        for _ in range(repeats):
            env.reset(seed=seed)
            with recording() as recorder:
                start = time.process_time()
                env.step(np.zeros(env.action_space.shape, np.float32))
                episode = time.process_time() - start
            bare = _replay(env, seed, recorder.targets, recorder.fine)
            best = {"episode": min(best["episode"], episode), "core": min(best["core"], recorder.core_seconds),
                    "bare": min(best["bare"], bare)}
        rows.append({"seed": seed, "steps": len(recorder.targets), **best})
    env.close()
    total = {key: float(sum(r[key] for r in rows)) for key in ("episode", "core", "bare")}
    return {"contexts": rows, "episode_over_bare": total["episode"] / total["bare"],
            "core_over_bare": total["core"] / total["bare"], "seconds": total}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--env-id", nargs="+", default=["rdmp_gym/ArmarWipe-v3", "rdmp_gym/PandaWipe-v3",
                                                        "rdmp_gym/ArmarWipe-v2", "rdmp_gym/ArmarDrum-v1",
                                                        "rdmp_gym/PandaDrum-v1"])
    parser.add_argument("--contexts", type=int, default=4, help="held-out contexts (reset seeds from 7000)")
    parser.add_argument("--repeats", type=int, default=3)
    add_save_argument(parser)
    args = parser.parse_args()
    seeds = list(range(7000, 7000 + args.contexts))
    result = {env_id: measure(env_id, seeds, args.repeats) for env_id in args.env_id}
    print(f"{'env':>26} {'episode s':>10} {'core s':>8} {'bare s':>8} {'episode/bare':>13} {'core/bare':>10}")
    for env_id, row in result.items():
        s = row["seconds"]
        print(f"{env_id:>26} {s['episode'] / len(seeds):10.3f} {s['core'] / len(seeds):8.3f} "
              f"{s['bare'] / len(seeds):8.3f} {row['episode_over_bare']:13.2f} {row['core_over_bare']:10.2f}")
    path = results_dir(args.save) / "sim_cost.json"
    path.write_text(json.dumps({"settings": vars(args), "results": result}, indent=1) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
