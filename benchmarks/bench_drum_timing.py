"""Where drumming's timing fails: one setting of the rhythm, the beats it misses, and what a reaction changes.

Per robot, the DMP's weights at the imitation, only the task's three rhythm values moving (the coupling ``K``, the
phase gain ``k_phi``, the beat's phase shift; action units):

- **the landscape**: a 5 x 5 x 5 grid of the three values on ``--grid-contexts`` training contexts (reset seeds
  5000...): the success rate and mean return of every point, and the **best setting** (most successes, then the
  highest return);
- **one setting for every context**: the best setting on ``--contexts`` other training contexts (reset seeds
  7000...): its success rate, mean absolute strike timing error, and where its failures are: each counted beat's
  timing error against the beats since the tempo change, and the failing contexts' tempo change (bpm);
- **reactions by hand** on the cycle-level face, from the best setting: the beat shift corrected in every cycle by
  the last played beat's timing error (proportional, ``shift = best - g e``, and accumulated, ``shift -= g e``), and
  the coupling raised for a cycle after an error above 30 ms; success, timing error and failure causes on the same
  contexts;
- **a retuned follower** (an oracle, on the task's version 2 with its fourth value ``tempo``,
  :mod:`rdmp_gym.envs.tasks.drumming.retuning`): at the first cycle that starts ``delay`` beats after the tempo
  change, the follower's frequency is set to the new tempo's (``CanonicalSchedule.resume(..., retune=)``), the rest
  as the best setting; how early a reaction must come;
- **retuned by ear** (no oracle): every cycle's tempo value ``2 log2(heard / announced)`` from the version 2
  cycle observation's heard tempo, the rest as the best setting;
- **the follower's ear** (version 2's ``ear`` value at 1, one episodic action): with the imitation's rhythm and
  with the best setting.

An episodic policy observes the context (the drum's pose, the announced tempo), not the tempo change to come: no
action chosen once per episode can fit both a rise and a fall of the tempo, so its ceiling is below the per-context
search's (``bench_drum.py``, which knows each context's change through its return).

    python benchmarks/bench_drum_timing.py --save        # both robots, about 10 min on 2 cores
    python benchmarks/bench_drum_timing.py --robots armar3 --grid-contexts 4 --contexts 8 --reactions proportional
    python benchmarks/bench_drum_timing.py --version-2-only --save     # add the version 2 probes to the saved study
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import gymnasium as gym
import numpy as np
import rdmp_gym.envs  # noqa: F401  (registers the ids)
from output import add_save_argument, results_dir
from rdmp_gym.agents.protocol import interval
from rdmp_gym.envs.registration import cycle_id

ROBOTS = {"armar3": "rdmp_gym/ArmarDrum-v1", "panda": "rdmp_gym/PandaDrum-v1"}
RHYTHM = ("coupling", "phase_gain", "phase")
GRID = np.linspace(-1.0, 1.0, 5)
GRID_SEEDS, CHECK_SEEDS = 5000, 7000
#: reaction -> (which value, rule, gain): the cycle face's hand-made reactions from the best setting
REACTIONS = {"proportional": ("phase", "proportional", 3.0), "accumulated": ("phase", "accumulated", 2.0),
             "coupling boost": ("coupling", "boost", 0.5)}
#: the cycle observation's column of the last played beat's timing error (s), counted from the end
_LAST_ERROR = -3
_BOOST_ERROR = 0.03
FIGURE = Path(__file__).resolve().parent.parent / "docs" / "assets" / "drum_timing.png"
#: the retuned follower's delays after the tempo change (beats at the new tempo)
RETUNE_DELAYS = (0.0, 0.5, 1.0)
#: the drumming task's version 2 (its tempo value and the heard tempo) on each robot
RETUNING = {"armar3": "rdmp_gym/ArmarDrum-v2", "panda": "rdmp_gym/PandaDrum-v2"}
#: the version 2 cycle observation's column of the heard tempo (before the cycle's place in the episode)
_HEARD = -2
#: the hand-made retune from the heard tempo: ``tempo = 2 log2(heard / announced)`` is the heard tempo's value
HEARD_GAIN = 2.0


def retuned(robot: str, best: np.ndarray, delay: float, contexts: int) -> dict:
    """The best setting with the follower retuned to the new tempo at the first cycle starting ``delay`` beats
    after the change (an oracle on the version 2 cycle face: its tempo value), on the check contexts."""
    env = gym.make(cycle_id(RETUNING[robot])).unwrapped
    results = []
    for i in range(contexts):
        env.reset(seed=CHECK_SEEDS + i)
        context, action = env.face.context, _action(env, best)              # its tempo value (the last) 0
        react_at = context.change_time + delay * 60.0 / context.new_tempo
        for cycle in range(env.n_cycles):
            if cycle > 0 and env.starts[cycle] >= react_at and action[-1] == 0.0:
                action = action.copy()
                action[-1] = np.clip(2.0 * np.log2(context.new_tempo / context.tempo), -1.0, 1.0) or 1e-9
            _, _, terminated, _, info = env.step(action)
            if terminated:
                break
        results.append(_outcome(info))
    env.close()
    return _scored(results) | {"delay_beats": delay}


def heard(robot: str, best: np.ndarray, gain: float, contexts: int) -> dict:
    """The best setting with every cycle's tempo value ``gain`` times the heard tempo (the version 2 cycle
    observation's last state entry, ``log2`` of the heard over the announced tempo), on the check contexts."""
    env = gym.make(cycle_id(RETUNING[robot])).unwrapped
    results = []
    for i in range(contexts):
        observation, _ = env.reset(seed=CHECK_SEEDS + i)
        action = _action(env, best)
        for _ in range(env.n_cycles):
            action = action.copy()
            action[-1] = np.clip(gain * observation[_HEARD], -1.0, 1.0)
            observation, _, terminated, _, info = env.step(action)
            if terminated:
                break
        results.append(_outcome(info))
    env.close()
    return _scored(results) | {"gain": gain}


def ear(robot: str, rhythm: np.ndarray, gain: float, contexts: int) -> dict:
    """The episodic action with the rhythm values ``rhythm [3]``, the version 2 ear at ``gain`` and every other
    dimension at the imitation, on the check contexts."""
    env = gym.make(RETUNING[robot])
    action = _action(env, rhythm)
    action[env.unwrapped.action_slices()["ear"]] = gain
    results = []
    for i in range(contexts):
        env.reset(seed=CHECK_SEEDS + i)
        info = env.step(action)[4]
        results.append(_outcome(info))
    env.close()
    return _scored(results) | {"rhythm": np.asarray(rhythm, dtype=float).tolist(), "gain": gain}


def version_2(robot: str, best: np.ndarray, contexts: int) -> dict:
    """The version 2 probes from the best setting ``best [3]``: the retune by ear on the cycle face, and the
    episodic ear at gain 1 with the imitation's rhythm and with the best setting."""
    return {"heard": heard(robot, best, HEARD_GAIN, contexts),
            "ear": [ear(robot, np.zeros(3), 1.0, contexts), ear(robot, best, 1.0, contexts)]}


def _outcome(info: dict) -> tuple[bool, float, float, list[str]]:
    """What a probe keeps of an episode's last ``info``: success, mean timing error, jerk ratio, failure causes."""
    return (bool(info["is_success"]), float(info["mean_abs_timing_error"]), float(info["jerk_ratio"]),
            list(info["failure_causes"]))


def _scored(results: list[tuple[bool, float, float, list[str]]]) -> dict:
    """Success (mean with its interval), mean timing error and jerk ratio, failure causes of a probe's episodes."""
    causes: dict[str, int] = {}
    for *_, failed in results:
        for cause in failed:
            causes[cause] = causes.get(cause, 0) + 1
    return {"success": interval(np.array([r[0] for r in results], dtype=float), statistic="mean").to_dict(),
            "timing_error": float(np.nanmean([r[1] for r in results])),
            "jerk_ratio": float(np.mean([r[2] for r in results])), "failure_causes": causes}


def _action(env, values: np.ndarray) -> np.ndarray:
    """The action ``[n]`` with the rhythm values ``[3]`` and every other dimension at the imitation."""
    face = env.unwrapped
    slices = getattr(face, "face", face).action_slices()           # the episodic face's, or the cycle face's own
    action = np.zeros(env.action_space.shape)
    for name, value in zip(RHYTHM, values, strict=True):
        action[slices[name]] = value
    return action


def _grid_context(job: tuple[str, int]) -> list[list[float]]:
    """Every grid point's ``[coupling, phase_gain, phase, success, return]`` in the context of reset seed."""
    env_id, seed = job
    env = gym.make(env_id)
    rows = []
    for values in itertools.product(GRID, GRID, GRID):
        env.reset(seed=seed)
        _, reward, _, _, info = env.step(_action(env, np.array(values)))
        rows.append([*values, float(info["is_success"]), float(reward)])
    env.close()
    return rows


def landscape(env_id: str, contexts: int, workers: int) -> dict:
    """The grid's success rate and mean return per point over ``contexts`` training contexts, and the best point."""
    with ProcessPoolExecutor(workers) as pool:
        per_context = np.array(list(pool.map(_grid_context, [(env_id, GRID_SEEDS + i) for i in range(contexts)])))
    success, returns = per_context[..., 3].mean(axis=0), per_context[..., 4].mean(axis=0)
    best = int(np.lexsort((returns, success))[-1])
    return {"points": per_context[0, :, :3].tolist(), "success": success.tolist(), "return": returns.tolist(),
            "best": per_context[0, best, :3].tolist(), "best_success": float(success[best]),
            "zero_success": float(success[_zero_index()]), "contexts": contexts}


def _zero_index() -> int:
    return [tuple(p) for p in itertools.product(GRID, GRID, GRID)].index((0.0, 0.0, 0.0))


def _beats_since_change(info: dict) -> np.ndarray:
    """Each beat's index counted from the first beat at the new tempo (0) ``[B]``."""
    beats = np.asarray(info["beat_times"])
    first_new = int(np.searchsorted(beats, info["change_time"] + 1e-9))
    return np.arange(beats.size) - first_new


def one_setting(env_id: str, best: np.ndarray, contexts: int) -> dict:
    """The best setting on ``contexts`` other training contexts: success, timing error, failures located."""
    env = gym.make(env_id)
    action, rows = _action(env, best), []
    for i in range(contexts):
        env.reset(seed=CHECK_SEEDS + i)
        _, reward, _, _, info = env.step(action)
        counted = np.asarray(info["counted_beats"], dtype=bool)
        rows.append({"seed": CHECK_SEEDS + i, "success": bool(info["is_success"]), "return": float(reward),
                     "timing_error": float(info["mean_abs_timing_error"]),
                     "tempo_change": float(info["new_tempo"] - info["tempo"]),
                     "causes": list(info["failure_causes"]),
                     "beats_since_change": _beats_since_change(info)[counted].tolist(),
                     "beat_errors": np.nan_to_num(np.asarray(info["timing_error"])[counted], nan=1.0).tolist()})
    env.close()
    success = np.array([row["success"] for row in rows], dtype=float)
    return {"success": interval(success, statistic="mean").to_dict(),
            "timing_error": float(np.nanmean([row["timing_error"] for row in rows])),
            "failed_tempo_changes": [row["tempo_change"] for row in rows if not row["success"]],
            "passed_tempo_changes": [row["tempo_change"] for row in rows if row["success"]], "rows": rows}


def _react(rule: str, gain: float, best: float, current: float, error: float) -> float:
    """The next cycle's value of a reaction's rhythm dimension after the last played beat's error (s)."""
    if rule == "proportional":
        return best - gain * error
    if rule == "accumulated":
        return current - gain * error
    return best + gain if abs(error) > _BOOST_ERROR else best


def reaction(env_id: str, best: np.ndarray, name: str, contexts: int) -> dict:
    """A hand-made reaction (:data:`REACTIONS`) on the cycle face from the best setting, on the check contexts."""
    which, rule, gain = REACTIONS[name]
    env = gym.make(cycle_id(env_id)).unwrapped
    index = RHYTHM.index(which)
    results = []
    for i in range(contexts):
        observation, _ = env.reset(seed=CHECK_SEEDS + i)
        values = np.array(best, dtype=float)
        for cycle in range(env.n_cycles):
            if cycle > 0:
                values[index] = np.clip(_react(rule, gain, best[index], values[index],
                                               float(observation[_LAST_ERROR])), -1.0, 1.0)
            observation, _, terminated, _, info = env.step(_action(env, values))
            if terminated:
                break
        results.append(_outcome(info))
    env.close()
    return {"rule": rule, "value": which, "gain": gain, **_scored(results)}


def figure(results: dict, out: Path) -> None:
    """Per robot: the grid's success over coupling x phase gain at the best shift, and the best setting's absolute
    timing error per counted beat against the beats since the tempo change."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, len(results), figsize=(5.2 * len(results), 8), squeeze=False)
    for column, result in enumerate(results.values()):
        grid = result["landscape"]
        points, success = np.array(grid["points"]), np.array(grid["success"])
        plane = np.isclose(points[:, 2], grid["best"][2])
        image = success[plane].reshape(len(GRID), len(GRID))          # rows: coupling, columns: phase gain
        ax = axes[0, column]
        shown = ax.imshow(image, origin="lower", extent=(-1.125, 1.125, -1.125, 1.125), vmin=0, vmax=1, cmap="viridis")
        ax.set_xlabel("phase gain (action)")
        ax.set_ylabel("coupling (action)")
        name = result["env"].split("/")[1]
        ax.set_title(f"{name}: success, beat shift {grid['best'][2]:+.1f}\n({grid['contexts']} training contexts)",
                     fontsize=10)
        fig.colorbar(shown, ax=ax, fraction=0.046)
        ax = axes[1, column]
        for row in result["one_setting"]["rows"]:
            errors = 1000 * np.abs(row["beat_errors"])
            ax.plot(row["beats_since_change"], errors, "-o", ms=3, lw=0.8,
                    color="tab:red" if not row["success"] else "0.7", alpha=0.9 if not row["success"] else 0.5)
        ax.axhline(50, color="k", ls="--", lw=1)
        ax.set_ylim(0, 160)
        ax.set_xlabel("counted beat, from the first at the new tempo (0)")
        ax.set_ylabel("|strike - beat| (ms)")
        ax.set_title(f"the best setting on {len(result['one_setting']['rows'])} other contexts (red: failed; "
                     "dashed: tolerance)", fontsize=9)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)


def _print_version_2(result: dict) -> None:
    rows = [("retuned every cycle to the heard tempo", result["heard"])]
    rows += [(f"ear {row['gain']:.1f}, rhythm {row['rhythm']}", row) for row in result["ear"]]
    for name, row in rows:
        print(f"    {name}: success {row['success']['estimate']:.3f}, timing error "
              f"{1000 * row['timing_error']:.1f} ms, failures {row['failure_causes']}")


def _only_version_2(args: argparse.Namespace) -> None:
    """Add the version 2 probes to the saved study (its best settings), without running the rest again."""
    path = results_dir(args.save) / "drum_timing.json"
    saved = json.loads(path.read_text())
    for robot in args.robots:
        result = saved["robots"][robot]
        result.update(version_2(robot, np.array(result["landscape"]["best"]), len(result["one_setting"]["rows"])))
        print(f"{result['env']}: best setting {result['landscape']['best']}")
        _print_version_2(result)
    path.write_text(json.dumps(saved, indent=1))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", nargs="+", choices=ROBOTS, default=list(ROBOTS))
    parser.add_argument("--grid-contexts", type=int, default=12)
    parser.add_argument("--contexts", type=int, default=40)
    parser.add_argument("--reactions", nargs="*", choices=REACTIONS, default=list(REACTIONS))
    parser.add_argument("--retune-delays", nargs="*", type=float, default=list(RETUNE_DELAYS))
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--version-2-only", action="store_true",
                        help="add the version 2 probes to the saved study (its best settings and context count)")
    add_save_argument(parser)
    args = parser.parse_args()
    if args.version_2_only:
        _only_version_2(args)
        return
    results = {}
    for robot in args.robots:
        env_id = ROBOTS[robot]
        grid = landscape(env_id, args.grid_contexts, args.workers)
        best = np.array(grid["best"])
        checked = one_setting(env_id, best, args.contexts)
        reacted = {name: reaction(env_id, best, name, args.contexts) for name in args.reactions}
        retunes = [retuned(robot, best, delay, args.contexts) for delay in args.retune_delays]
        results[robot] = {"env": env_id, "landscape": grid, "one_setting": checked, "reactions": reacted,
                          "retuned": retunes, **version_2(robot, best, args.contexts)}
        rate = checked["success"]
        print(f"{env_id}: grid best {best.tolist()} ({grid['best_success']:.2f} of the grid contexts, imitation "
              f"{grid['zero_success']:.2f}); on {args.contexts} other contexts: success "
              f"{rate['estimate']:.3f} [{rate['low']:.3f}, {rate['high']:.3f}], timing error "
              f"{1000 * checked['timing_error']:.1f} ms; failed tempo changes (bpm) "
              f"{np.round(checked['failed_tempo_changes'], 1).tolist()}")
        for name, row in reacted.items():
            print(f"    reaction {name:>14}: success {row['success']['estimate']:.3f}, timing error "
                  f"{1000 * row['timing_error']:.1f} ms, jerk {row['jerk_ratio']:.2f}, "
                  f"failures {row['failure_causes']}")
        for row in retunes:
            print(f"    retuned {row['delay_beats']:.1f} beats after the change: success "
                  f"{row['success']['estimate']:.3f}, timing error {1000 * row['timing_error']:.1f} ms, "
                  f"failures {row['failure_causes']}")
        _print_version_2(results[robot])
    out = results_dir(args.save)
    (out / "drum_timing.json").write_text(json.dumps({"settings": vars(args), "robots": results}, indent=1))
    figure(results, FIGURE if args.save else out / "drum_timing.png")


if __name__ == "__main__":
    main()
