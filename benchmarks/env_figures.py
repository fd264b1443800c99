"""The figures of what the paper leaves open that need the MuJoCo environment: force-profile learning on a tilted
and a curved table (``beyond_force.png``) and the coupling baseline that lifts the sponge over the cup
(``beyond_obstacle.png``). The core's figures (the paper's, the stop, the rhythm) are ``python -m rdmp_gym.figures``.

    python benchmarks/env_figures.py --out figures/
"""

from __future__ import annotations

import argparse
import logging
import tempfile
from pathlib import Path

import gymnasium as gym
import numpy as np
from obstacle_baseline import lift_term, lifting_path
from rdmp_gym.envs import ENV_ID
from rdmp_gym.envs.tasks.wiping.force_learning import curved_table_scene, period_force_errors

from rdmp_gym.figures.paper import save_figure
from rdmp_gym.figures.plots import pyplot

__all__ = ["ENV_FIGURES", "write_force_figure", "write_obstacle_figure"]


def write_force_figure(out_dir: str | Path, seed: int = 0) -> Path:
    """``beyond_force.png``: force-profile learning in the MuJoCo env, the contact force at 500 Hz on a tilted and
    on a curved table."""
    tilt = [-0.138, -0.145]
    fig, (tilted, curved, bars) = pyplot().subplots(1, 3, figsize=(16, 4), gridspec_kw={"width_ratios": [3, 3, 2]})
    errors, colors = {}, {}
    with tempfile.TemporaryDirectory() as folder:
        scene = str(curved_table_scene(folder))
        runs = (("tilted", tilted, tilt, None, 0.02), ("curved", curved, [0.0, 0.0], scene, 0.02),
                ("tilted", None, tilt, None, 0.004))
        for table, axis, table_tilt, xml_file, gain in runs:
            for flag, color in ((False, "tab:gray"), (True, "tab:red" if gain == 0.02 else "tab:purple")):
                name = f"{table}, gain {gain}, " + ("+ learned profile" if flag else "admittance")
                env = gym.make(ENV_ID, n_periods=10.0, force_learning=flag, admittance_gain=gain, xml_file=xml_file)
                env.reset(seed=seed, options={"table_height": 0.0, "table_tilt": table_tilt, "patch_centre": [0.0, 0.0],
                                              "patch_size": [0.12, 0.12], "sponge_start": [-0.07, 0.10, 0.08],
                                              "obstacle": 0})
                inner = env.unwrapped
                inner.task.fine_force = True
                info = env.step(np.zeros(env.action_space.shape, dtype=np.float32))[4]
                fine_dt = inner.dt / inner.frame_skip
                force = info["fine_force_trace"]
                if axis is not None:
                    axis.plot(np.arange(force.size) * fine_dt, force, color=color, lw=0.8,
                              label=name.split(", ", 2)[2])
                errors[name] = period_force_errors(force, fine_dt, inner.dmp.transients[0].length, inner.dmp.period,
                                                   inner.task.reward_settings.target_force, smoothing=0.0)
                colors[name] = color if gain == 0.02 or flag else "tab:blue"
                env.close()
    for axis, title in ((tilted, f"table tilted by ({tilt[0]}, {tilt[1]}) rad"),
                        (curved, "curved table (ellipsoid top, crown 6 cm)")):
        axis.axhline(18.0, color="k", lw=0.8, ls="--")
        axis.set(xlabel="t [s]", ylabel="contact force at 500 Hz [N]", ylim=(14, 22),
                 title=f"default admittance (0.02): {title}")
        axis.legend(fontsize=8)
    width = 0.8 / len(errors)
    for index, (name, values) in enumerate(errors.items()):
        hatch = "//" if name.startswith("curved") else None
        bars.bar(np.arange(1, values.size + 1) + (index - (len(errors) - 1) / 2) * width, values, width,
                 label=name, color=colors[name], hatch=hatch, edgecolor="white" if hatch else None)
    bars.set(xlabel="period", ylabel="mean |F - 18 N| at 500 Hz [N]", title="force error period by period",
             yscale="log")
    bars.legend(fontsize=6)
    fig.tight_layout()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    return save_figure(fig, out / "beyond_force.png")


def write_obstacle_figure(out_dir: str | Path, seed: int = 0) -> Path:
    """``beyond_obstacle.png``: the imitation and the coupling baseline that lifts it over the cup, in the first
    ArmarWipe-v1 context from reset seed ``seed`` on with a cup."""
    env = gym.make(ENV_ID)
    inner = env.unwrapped
    context_seed = next(s for s in range(seed, seed + 1000) if env.reset(seed=s)[0][10] > 0.5)
    env.reset(seed=context_seed)
    term = lift_term(env)
    free = inner.rollout_path(inner.action_map.theta0)
    lifted, conservative = lifting_path(env), lifting_path(env, adaptive=False)
    env.close()
    fig, (side, top) = pyplot().subplots(1, 2, figsize=(12, 4.2), gridspec_kw={"width_ratios": [3, 2]})
    for path, name, color, style in ((free, "imitation", "tab:gray", "-"),
                                     (conservative, "LiftOver alone (full lift)", "tab:orange", "--"),
                                     (lifted, "coupling baseline (AdaptiveLift)", "tab:red", "-")):
        side.plot(inner.times, path[:, 2], color=color, ls=style, label=name)
        top.plot(path[:, 0], path[:, 1], color=color, ls=style, lw=0.8)
    near = np.linalg.norm(free[:, :2] - term.centre, axis=1) < term.radius + term.reach
    side.fill_between(inner.times, 0.0, term.top, where=near, color="tab:brown", alpha=0.3,
                      label="cup's height where the sponge is over its footprint")
    side.plot(inner.times, term.gate(inner.times) * term.lift, color="tab:blue", ls=":", lw=1,
              label="gate x (top + clearance)")
    side.set(xlabel="t [s]", ylabel="sponge height above the table [m]", xlim=(0, 3.5),
             title=f"ArmarWipe-v1, reset seed {context_seed}")
    side.legend(fontsize=8)
    angles = np.linspace(0.0, 2.0 * np.pi, 100)
    for radius, style in ((term.radius, "-"), (term.radius + term.reach, "--"),
                          (term.radius + term.reach + term.ramp, ":")):
        top.plot(term.centre[0] + radius * np.cos(angles), term.centre[1] + radius * np.sin(angles), "k", ls=style,
                 lw=0.8)
    top.set(xlabel="x [m]", ylabel="y [m]", title="cup, + sponge reach, + ramp (top view)")
    top.set_aspect("equal")
    fig.tight_layout()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    return save_figure(fig, out / "beyond_obstacle.png")


ENV_FIGURES = [write_force_figure, write_obstacle_figure]
"""The environment's figures of what the paper leaves open (each ``(out_dir, seed) -> Path``)."""


def main(argv: list[str] | None = None) -> None:
    """Command-line entry: ``python benchmarks/env_figures.py --out DIR``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="figures", help="output folder (default: figures)")
    parser.add_argument("--seed", type=int, default=0, help="reset seed of the first context")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    for write in ENV_FIGURES:
        print(write(args.out, args.seed))


if __name__ == "__main__":
    main()
