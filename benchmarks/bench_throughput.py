"""Throughput of the wiping episodes: 1 process, the local pool and Ray; overhead per task; the physics limit.

Three measurements, each repeated ``--repeats`` times with the variants interleaved (so that a change
of load on a shared machine hits every variant alike):

1. **Episodes per second** of one batch (``--episodes`` default episodes of ``rdmp_gym/ArmarWipe-v1``,
   random actions of std 0.1, fixed seeds) on one process, on the local pool (``--workers`` processes)
   and on Ray (``--workers`` actors; a new local instance, or ``--ray-address``). Besides the wall
   time, the CPU time of every process involved (this one and the workers, from ``/proc``) is
   counted: CPU seconds per episode do not depend on what else runs on the machine, and
   ``workers / (CPU s per episode)`` is the throughput the backend would reach with ``workers`` idle cores.
   All variants return the same numbers (checked).
2. **Overhead per task**: round trips of a task that does no work (``os.getpid``), one at a time
   (latency) and ``--episodes`` at once (throughput), on each backend.
3. **Episode vs bare physics**: one episode (``step``, reset excluded) against bare ``mujoco.mj_step``
   replaying the same controls from the same state (captured from the episode's own ``mj_step`` calls,
   so this does not depend on the env's internals); ratio of CPU times, median and spread; and a
   profile of where the rest of the episode's time goes.

Prints tables and writes ``benchmarks/results/throughput.json``. On a quiet machine::

    MUJOCO_GL=egl python benchmarks/bench_throughput.py --workers 2 --repeats 5
    RAY_ADDRESS=auto python benchmarks/bench_throughput.py --workers 64      # on a Ray cluster
"""

from __future__ import annotations

import argparse
import cProfile
import json
import os
import platform
import pstats
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import gymnasium as gym
import mujoco
import numpy as np
import rdmp_gym.envs  # noqa: F401  (registers the env)
from output import add_save_argument, results_dir
from rdmp_gym.agents.pool import Evaluator
from rdmp_gym.agents.tasks import WIPE_ID, TaskSpec

_TICK = os.sysconf("SC_CLK_TCK")


def process_cpu_seconds(pids: Sequence[int]) -> float:
    """User + system CPU seconds so far of processes ``pids`` (Linux ``/proc``; 0 for one that is gone)."""
    total = 0
    for pid in pids:
        try:
            fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        total += int(fields[11]) + int(fields[12])
    return total / _TICK


def _worker_pids(evaluator: Evaluator) -> list[int]:
    pool = evaluator._pool
    if pool is None:
        return []
    if evaluator.backend == "ray":
        import ray

        return sorted(set(ray.get([actor.ping.remote() for actor in pool.actors])))
    return [process.pid for process in pool._executor._processes.values()]


# ---------------------------------------------------------------------------------------------- throughput
def _timed_batch(evaluator: Evaluator, actions: np.ndarray, seeds: np.ndarray, pids: list[int]
                 ) -> tuple[float, float, np.ndarray]:
    """(wall s, CPU s of this process and the workers, returns) of one batch."""
    cpu0, workers0, wall0 = time.process_time(), process_cpu_seconds(pids), time.perf_counter()
    batch = evaluator.run(actions, seeds)
    wall = time.perf_counter() - wall0
    cpu = time.process_time() - cpu0 + process_cpu_seconds(pids) - workers0
    return wall, cpu, batch.returns


def _round_trips(evaluator: Evaluator, count: int) -> tuple[float, float]:
    """(latency, throughput cost) in seconds per task of a task that does no work."""
    pool = evaluator._pool
    if evaluator.backend == "ray":
        import ray

        actor = pool.actors[0]
        start = time.perf_counter()
        for _ in range(count):
            ray.get(actor.ping.remote())
        latency = (time.perf_counter() - start) / count
        start = time.perf_counter()
        ray.get([pool.actors[i % len(pool.actors)].ping.remote() for i in range(count)])
        return latency, (time.perf_counter() - start) / count
    executor = pool._executor
    start = time.perf_counter()
    for _ in range(count):
        executor.submit(os.getpid).result()
    latency = (time.perf_counter() - start) / count
    start = time.perf_counter()
    for future in [executor.submit(os.getpid) for _ in range(count)]:
        future.result()
    return latency, (time.perf_counter() - start) / count


def throughput(spec: TaskSpec, workers: int, episodes: int, repeats: int, ray_address: str | None,
               use_ray: bool) -> dict[str, Any]:
    """Episodes per second and CPU seconds per episode of each backend, interleaved over ``repeats``."""
    variants = {"1 process": (1, "local", None), f"local pool x{workers}": (workers, "local", None)}
    if use_ray:
        variants[f"ray x{workers}"] = (workers, "ray", ray_address)
    evaluators: dict[str, Evaluator] = {}
    started: dict[str, float] = {}
    try:
        for name, (count, backend, address) in variants.items():
            begin = time.perf_counter()
            evaluators[name] = Evaluator(spec, count, backend, address)
            n = evaluators[name].n_actions
            evaluators[name].run(np.zeros((count, n)), np.arange(count))       # build every worker's env
            started[name] = time.perf_counter() - begin
        rng = np.random.default_rng(0)
        actions = np.clip(0.1 * rng.standard_normal((episodes, n)), -1, 1)
        seeds = np.arange(episodes) + 1000
        pids = {name: _worker_pids(ev) for name, ev in evaluators.items()}
        samples: dict[str, list[tuple[float, float]]] = {name: [] for name in evaluators}
        reference = None
        for _ in range(repeats):
            for name, evaluator in evaluators.items():
                wall, cpu, returns = _timed_batch(evaluator, actions, seeds, pids[name])
                samples[name].append((wall, cpu))
                if reference is None:
                    reference = returns
                elif not np.array_equal(returns, reference):
                    raise AssertionError(f"{name}: the returns differ from the other backends'")
        overhead = {name: _round_trips(ev, max(episodes, 32)) for name, ev in evaluators.items()
                    if ev._pool is not None}
    finally:
        for evaluator in evaluators.values():
            evaluator.close()
    rows = []
    base_wall = float(np.median([w for w, _ in samples["1 process"]]))
    base_cpu = float(np.median([c for _, c in samples["1 process"]])) / episodes
    for name, values in samples.items():
        wall = np.array([w for w, _ in values])
        cpu_per_episode = np.array([c for _, c in values]) / episodes
        count = variants[name][0]
        rows.append({"variant": name, "workers": count, "startup_s": started[name],
                     "episodes_per_s": float(episodes / np.median(wall)),
                     "episodes_per_s_range": [float(episodes / wall.max()), float(episodes / wall.min())],
                     "speedup_wall": float(base_wall / np.median(wall)),
                     "cpu_s_per_episode": float(np.median(cpu_per_episode)),
                     "idle_cores_episodes_per_s": float(count / np.median(cpu_per_episode)),
                     "idle_cores_speedup": float(count * base_cpu / np.median(cpu_per_episode)),
                     "task_latency_s": overhead[name][0] if name in overhead else None,
                     "task_cost_s": overhead[name][1] if name in overhead else None})
    return {"episodes": episodes, "repeats": repeats, "rows": rows}


# ---------------------------------------------------------------------------------------------- physics
class _StepRecorder:
    """Wraps ``mujoco.mj_step``: keeps the state before the first call and the controls of every call."""

    def __init__(self) -> None:
        self.original = mujoco.mj_step
        self.calls: list[tuple[np.ndarray, int]] = []
        self.state: np.ndarray | None = None
        self.model: Any = None
        self.data: Any = None
        self.final_qpos: np.ndarray | None = None

    def __call__(self, model: Any, data: Any, nstep: int = 1) -> None:
        if self.state is None:
            self.model, self.data = model, data
            spec = mujoco.mjtState.mjSTATE_INTEGRATION
            self.state = np.empty(mujoco.mj_stateSize(model, spec))
            mujoco.mj_getState(model, data, self.state, spec)
        self.calls.append((data.ctrl.copy(), nstep))
        self.original(model, data, nstep)


def _record_episode(env: gym.Env, action: np.ndarray, seed: int, options: dict | None) -> _StepRecorder:
    recorder = _StepRecorder()
    env.reset(seed=seed, options=options)
    mujoco.mj_step = recorder
    try:
        env.step(action)
    finally:
        mujoco.mj_step = recorder.original
    if recorder.state is None:
        raise RuntimeError("the episode made no mj_step call (an invalid action?)")
    recorder.final_qpos = recorder.data.qpos.copy()
    return recorder


def _bare(recorder: _StepRecorder) -> tuple[float, float]:
    """(wall, CPU) seconds of replaying the recorded controls with nothing but ``mj_step``."""
    model, data, step = recorder.model, recorder.data, mujoco.mj_step
    mujoco.mj_setState(model, data, recorder.state, mujoco.mjtState.mjSTATE_INTEGRATION)
    wall, cpu = time.perf_counter(), time.process_time()
    for ctrl, nstep in recorder.calls:
        data.ctrl[:] = ctrl
        step(model, data, nstep)
    return time.perf_counter() - wall, time.process_time() - cpu


def physics_limit(env: gym.Env, action: np.ndarray, seed: int, options: dict | None, repeats: int
                  ) -> dict[str, Any]:
    """Episode (``step`` only) vs bare ``mj_step`` of the same controls from the same state, interleaved.

    Returns medians and ranges of wall and CPU time and their ratios over ``repeats`` repetitions.
    """
    recorder = _record_episode(env, action, seed, options)
    episode_wall, episode_cpu, bare_wall, bare_cpu = [], [], [], []
    for _ in range(repeats):
        env.reset(seed=seed, options=options)
        wall, cpu = time.perf_counter(), time.process_time()
        env.step(action)
        episode_wall.append(time.perf_counter() - wall)
        episode_cpu.append(time.process_time() - cpu)
        wall, cpu = _bare(recorder)
        bare_wall.append(wall)
        bare_cpu.append(cpu)
    same_physics = bool(np.array_equal(recorder.data.qpos, recorder.final_qpos))     # the replay's end state
    ratio_cpu = np.array(episode_cpu) / np.array(bare_cpu)
    ratio_wall = np.array(episode_wall) / np.array(bare_wall)
    physics_steps = sum(nstep for _, nstep in recorder.calls)
    return {"repeats": repeats, "physics_steps": physics_steps, "control_steps": len(recorder.calls),
            "replay_reaches_the_episode_end_state": same_physics,
            "episode_cpu_s": float(np.median(episode_cpu)), "bare_cpu_s": float(np.median(bare_cpu)),
            "episode_wall_s": float(np.median(episode_wall)), "bare_wall_s": float(np.median(bare_wall)),
            "ratio_cpu_median": float(np.median(ratio_cpu)),
            "ratio_cpu_range": [float(ratio_cpu.min()), float(ratio_cpu.max())],
            "ratio_wall_median": float(np.median(ratio_wall)),
            "ratio_wall_range": [float(ratio_wall.min()), float(ratio_wall.max())]}


_PARTS: dict[str, Callable[[str, str], bool]] = {
    "mj_step (physics)": lambda file, name: name == "<built-in method mujoco._functions.mj_step>",
    "DMP rollout": lambda file, name: name == "rollout_batch",
    "path IK (PathIK.solve)": lambda file, name: name == "solve" and file.endswith("ik.py"),
    "dirt bookkeeping (wear after the loop)": lambda file, name: name == "_removal" and file.endswith("simulation.py"),
    "reward": lambda file, name: name == "wipe_reward",
    "simulation loop, own Python": lambda file, name: (
        (name in ("simulate_wipe", "command", "substeps", "substep", "finish") and file.endswith("simulation.py"))
        or (name in ("run", "step") and file.endswith("servo.py"))),
}


def episode_profile(env: gym.Env, action: np.ndarray, seed: int, options: dict | None, repeats: int
                    ) -> dict[str, float]:
    """Seconds per episode in the parts of ``step`` (cumulative, except the loop's own Python: tottime)."""
    profiler = cProfile.Profile()
    for _ in range(repeats):
        env.reset(seed=seed, options=options)
        profiler.enable()
        env.step(action)
        profiler.disable()
    stats = pstats.Stats(profiler).stats
    parts = {name: 0.0 for name in _PARTS}
    total = 0.0
    for (file, _, function), (_, _, tottime, cumtime, _) in stats.items():
        if function == "step" and file.endswith(("wiping/env.py", "wiping\\env.py")):
            total = cumtime
        for name, match in _PARTS.items():
            if match(file, function):
                parts[name] += tottime if name.endswith("own Python") or name.startswith("mj_step") else cumtime
    parts["step total (profiled)"] = total
    return {name: value / repeats for name, value in parts.items()}


# ---------------------------------------------------------------------------------------------- main
def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1, help="pool processes and Ray actors")
    parser.add_argument("--episodes", type=int, default=0, help="episodes per batch (default 4 x workers)")
    parser.add_argument("--repeats", type=int, default=5, help="interleaved repetitions (>= 5)")
    parser.add_argument("--ray-address", default=None, help="Ray cluster (default $RAY_ADDRESS, else a local one)")
    parser.add_argument("--no-ray", action="store_true", help="skip the Ray backend")
    parser.add_argument("--env-option", action="append", default=[], metavar="KEY=VALUE",
                        help="a gym.make keyword of the env (default: its defaults)")
    parser.add_argument("--out", type=Path, default=None, help="result file (default: throughput.json, see --save)")
    add_save_argument(parser)
    args = parser.parse_args()
    args.out = args.out or results_dir(args.save) / "throughput.json"
    env_kwargs = {key: json.loads(value) for key, value in (item.split("=", 1) for item in args.env_option)}
    episodes = args.episodes or 4 * args.workers
    use_ray = not args.no_ray
    if use_ray:
        try:
            import ray  # noqa: F401
        except ImportError:
            print("ray is not installed (pip install 'rdmp-gym[ray]'): skipping the Ray backend")
            use_ray = False

    env = gym.make(WIPE_ID, disable_env_checker=True, **env_kwargs)
    options = {"table_height": 0.0, "table_tilt": [0.0, 0.0], "patch_centre": [0.0, 0.0],
               "patch_size": [0.12, 0.12], "sponge_start": [-0.07, 0.10, 0.08]}
    zero = np.zeros(env.action_space.shape, dtype=np.float32)
    env.reset(seed=0, options=options)
    env.step(zero)                                               # warm-up
    physics = physics_limit(env.unwrapped, zero, 0, options, max(5, args.repeats))
    parts = episode_profile(env.unwrapped, zero, 0, options, 3)
    env.close()
    result = throughput(TaskSpec(WIPE_ID, env_kwargs), args.workers, episodes, max(5, args.repeats),
                        args.ray_address, use_ray)

    document = {"machine": {"cpus": os.cpu_count(), "load_average_1min": os.getloadavg()[0],
                            "python": platform.python_version(), "mujoco": mujoco.__version__,
                            "processor": platform.processor() or platform.machine()},
                "settings": {**vars(args), "out": str(args.out), "episodes": episodes},
                "throughput": result, "physics": physics, "episode_parts_s": parts}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(document, indent=1) + "\n")

    print(f"throughput: batches of {episodes} episodes, {result['repeats']} interleaved repetitions, "
          f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}")
    print(f"{'variant':>16} {'start s':>8} {'episodes/s':>11} {'(range)':>13} {'speed-up':>8} "
          f"{'CPU s/episode':>13} {'idle-core ep/s':>14} {'idle speed-up':>13} {'task latency':>12} {'task cost':>10}")
    for row in result["rows"]:
        low, high = row["episodes_per_s_range"]
        latency = "-" if row["task_latency_s"] is None else f"{1e3 * row['task_latency_s']:.2f} ms"
        cost = "-" if row["task_cost_s"] is None else f"{1e3 * row['task_cost_s']:.2f} ms"
        print(f"{row['variant']:>16} {row['startup_s']:8.1f} {row['episodes_per_s']:11.2f} "
              f"{f'{low:.1f}-{high:.1f}':>13} {row['speedup_wall']:8.2f} {row['cpu_s_per_episode']:13.4f} "
              f"{row['idle_cores_episodes_per_s']:14.2f} {row['idle_cores_speedup']:13.2f} {latency:>12} {cost:>10}")
    print("(speed-up: wall time vs 1 process, distorted by other jobs on a shared machine; idle: from CPU time, "
          "workers / CPU s per episode)")
    print(f"\nepisode vs bare mj_step, same controls from the same state ({physics['control_steps']} control "
          f"steps, {physics['physics_steps']} physics steps), {physics['repeats']} interleaved repetitions:")
    print(f"  the replay ends in the episode's final state: {physics['replay_reaches_the_episode_end_state']}")
    low, high = physics["ratio_cpu_range"]
    print(f"  CPU:  episode {physics['episode_cpu_s']:.4f} s, bare {physics['bare_cpu_s']:.4f} s, "
          f"ratio median {physics['ratio_cpu_median']:.3f} (range {low:.3f}-{high:.3f}; target <= 1.2)")
    low, high = physics["ratio_wall_range"]
    print(f"  wall: episode {physics['episode_wall_s']:.4f} s, bare {physics['bare_wall_s']:.4f} s, "
          f"ratio median {physics['ratio_wall_median']:.3f} (range {low:.3f}-{high:.3f})")
    print("where the episode's time goes (cProfile, s per episode; profiling inflates Python-heavy parts):")
    for name, value in parts.items():
        print(f"  {name:40s}{value:9.4f}")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
