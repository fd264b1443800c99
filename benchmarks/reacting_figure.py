"""The reacting learner's validation curves beside the best open-loop learner's, from the committed results.

Per task one panel: each seed of the reacting learner (its open-loop stage dashed, the reacting stage solid, the stage
change marked), and the open-loop learner of the committed ten-seed table (IQM over its seeds with a 95 % bootstrap
band). Every curve is the validation success on the task's validation contexts (never the test contexts).

    python benchmarks/reacting_figure.py --out docs/assets/reacting_curves.png
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from output import COMMITTED
from rdmp_gym.agents.protocol import interval

#: title -> (the reacting learner's result, the open-loop learner's ten-seed result, its agent's name there)
PANELS = {
    "rdmp_gym/ArmarWipe-v3": ("reacting_pooled_feedback_armar_wipe_v3.json", "agents_v3_bbrl_ridge10.json",
                              "bbrl_ridge"),
    "rdmp_gym/PandaWipe-v3": ("reacting_panda_wipe_v3.json", "agents_panda_v3_bbrl_ridge.json", "bbrl_ridge"),
    "rdmp_gym/ArmarDrum-v1": ("reacting_armar_drum_v1.json", "agents_drum_armar.json", "plain_prior"),
}


def open_loop_band(document: dict, agent: str) -> tuple[np.ndarray, list[dict]]:
    """(episodes [M], the IQM with its interval at each) of ``agent``'s runs, at the marks they all share."""
    runs = [run for run in document["runs"] if run["agent"] == agent]
    marks = sorted(set.intersection(*({row["episodes"] for row in run["curve"]} for run in runs)))
    values = np.array([[next(row["eval_success"] for row in run["curve"] if row["episodes"] == m) for m in marks]
                       for run in runs])
    return np.asarray(marks), [interval(values[:, i]).to_dict() | {"n": len(runs)} for i in range(len(marks))]


def draw(axis: plt.Axes, env_id: str, reacting: dict, open_loop: dict, agent: str) -> None:
    marks, band = open_loop_band(open_loop, agent)
    axis.plot(marks, [b["estimate"] for b in band], color="C0", lw=2, label=f"`{agent}` alone (IQM, {band[0]['n']} "
              "seeds)")
    axis.fill_between(marks, [b["low"] for b in band], [b["high"] for b in band], color="C0", alpha=0.15)
    for k, (seed, curve) in enumerate(sorted(reacting["curves"].items())):
        episodes = np.array([row["episodes"] for row in curve])
        success = np.array([row["validation_success"] for row in curve])
        first = np.array([row.get("stage") == "open loop" for row in curve])
        last_open = int(np.flatnonzero(first)[-1])
        colour = f"C{k + 1}"
        axis.plot(episodes[:last_open + 1], success[:last_open + 1], color=colour, ls="--", lw=1)
        axis.plot(episodes[last_open:], success[last_open:], color=colour, lw=1.5,
                  label=f"reacting, seed {seed} (dashed: its open-loop stage)")
        axis.axvline(episodes[last_open], color="grey", lw=0.6, ls=":")
    test = reacting["test_success"]
    axis.set_title(f"{env_id}: reacting test {test['estimate']:.2f} ({test['n']} seeds)", fontsize=9)
    axis.set_xlabel("episodes")
    axis.set_ylabel("validation success")
    axis.set_ylim(-0.02, 1.02)
    axis.grid(alpha=0.3)
    axis.legend(fontsize=6.5, loc="lower right")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("runs/benchmarks/reacting_curves.png"))
    args = parser.parse_args()
    figure, axes = plt.subplots(1, len(PANELS), figsize=(5.2 * len(PANELS), 3.8))
    for axis, (env_id, (reacting, open_loop, agent)) in zip(axes, PANELS.items(), strict=True):
        draw(axis, env_id, json.loads((COMMITTED / reacting).read_text()),
             json.loads((COMMITTED / open_loop).read_text()), agent)
    figure.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
