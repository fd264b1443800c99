"""The environments' imitation DMPs do not change when the library's fit defaults do: they are fitted with the
settings the tasks were published with (``rdmp_gym.dmp.fitting.FADE_BEFORE_T``)."""

from pathlib import Path

import numpy as np
import pytest

from rdmp_gym import RhythmicDMP, wiping_demonstration

REFERENCE = Path(__file__).parent / "data" / "imitation_rollouts.npz"


@pytest.mark.parametrize("style", [1, 2, 3, 4])
def test_wipe_env_imitation_is_unchanged(style):
    """The DMP ArmarWipe-v1/v2 fit at make time (40 + 40 basis functions) rolls out as saved, to 1e-9 m."""
    from rdmp_gym.envs.tasks.wiping.task import _fit_style

    dmp = _fit_style(style, 40, 40, "trajectory")
    saved = np.load(REFERENCE)[f"style{style}_n40"]
    t = np.arange(saved.shape[0]) * 0.01
    np.testing.assert_allclose(dmp.rollout(t), saved, rtol=0.0, atol=1e-9)


def test_tracking_env_imitation_is_unchanged():
    from rdmp_gym.envs.tracking import TrackingEnv

    env = TrackingEnv()
    saved = np.load(REFERENCE)["style1_n15"]
    t = np.arange(saved.shape[0]) * 0.01
    np.testing.assert_allclose(env.dmp.rollout(t), saved, rtol=0.0, atol=1e-9)


def test_library_defaults_differ_from_the_pinned_fit():
    """The check above could not fail if the defaults were the pinned settings: they are not."""
    dmp = RhythmicDMP.fit(wiping_demonstration(style=1, rng=0))
    saved = np.load(REFERENCE)["style1_n40"]
    t = np.arange(saved.shape[0]) * 0.01
    assert np.max(np.abs(dmp.rollout(t) - saved)) > 1e-6
