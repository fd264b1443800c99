"""Fit a rhythmic DMP with a transient to a wiping demonstration and generalise it.

    python examples/fit_and_reproduce.py      # writes runs/examples/fit_and_reproduce.png
"""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rdmp_gym import RhythmicDMP, segment, wiping_demonstration

# 1. A demonstration: 10 s at 100 Hz of a 3-D wiping movement (x, y on the table, z height), with noise.
demo = wiping_demonstration(style=2, rng=0)

# 2. Segmentation (paper IV): period, transient length and anchor, estimated from the samples.
seg = segment(demo)
print(f"period {seg.period:.3f} s, transient {seg.transient_length:.2f} s, anchor {np.round(seg.anchor, 4)}")

# 3. Fit: 40 periodic + 40 transient basis functions, global ridge regression.
dmp = RhythmicDMP.fit(demo, n_periodic=40, n_transient=40, method="ridge", segmentations=[seg])

# 4. Reproduce, and generalise: new anchor, bigger and rotated pattern, half speed.
t = np.arange(0.0, 12.0, 0.01)
original = dmp.rollout(t)
moved = dmp.rollout(t, anchor=dmp.anchor + np.array([0.15, -0.05, 0.0]), scale=1.4, rotation=np.pi / 6)
slow = dmp.rollout(t, tempo=0.5)

# 5. Online execution with feedback: a coupling term pushes z up while the stepper runs.
stepper = dmp.start(dt=0.01)
online = np.array([stepper.step(coupling=np.array([0.0, 0.0, 20.0]))[0] for _ in t])

fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.5))
left.plot(demo.Y[:, 0], demo.Y[:, 1], lw=3, alpha=0.3, label="demonstration")
left.plot(original[:, 0], original[:, 1], label="reproduction")
left.plot(moved[:, 0], moved[:, 1], label="new anchor, x1.4, rotated 30°")
left.set(aspect="equal", xlabel="x [m]", ylabel="y [m]")
left.legend(fontsize=8)
right.plot(t, original[:, 2], label="z, reproduction")
right.plot(t, slow[:, 2], label="z, half speed")
right.plot(t, online[:, 2], label="z, with coupling term")
right.set(xlabel="t [s]", ylabel="z [m]")
right.legend(fontsize=8)
fig.tight_layout()
out = Path("runs/examples/fit_and_reproduce.png")
out.parent.mkdir(parents=True, exist_ok=True)
fig.savefig(out, dpi=100)
print(f"wrote {out}")
