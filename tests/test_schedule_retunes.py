"""The follower's scheduled frequency corrections (rdmp_gym.dmp.frequency.Retunes) in a canonical schedule: what a
correction sets, that a resumed schedule keeps them bit for bit, and that the path stays smooth across one."""

import numpy as np
import pytest
from rdmp_gym.envs.tasks.drumming.task import DrumTask

from rdmp_gym.dmp.frequency import CanonicalSchedule, Retunes

DT = 0.01
STEPS = 800
#: the input: a beat at 1.6 Hz that jumps to 1.3 Hz at 3 s
TIMES = np.arange(STEPS) * DT
PHASE = 2 * np.pi * (1.6 * np.minimum(TIMES, 3.0) + 1.3 * np.maximum(TIMES - 3.0, 0.0))
SIGNAL = np.cos(PHASE)
SETTINGS = {"coupling": 4.0, "phase_gain": 4.0, "frequency": 2 * np.pi * 1.6}


@pytest.fixture(scope="module")
def dmp():
    return DrumTask().imitation()


def _heard(gain: float) -> Retunes:
    """A correction every 0.625 s from 1 s on to the input's frequency there."""
    steps = np.arange(100, STEPS, 62)
    return Retunes(steps, np.where(TIMES[steps] > 3.0, 2 * np.pi * 1.3, 2 * np.pi * 1.6), gain)


def test_a_correction_moves_the_frequency_its_share_of_the_way(dmp):
    plain = CanonicalSchedule.record(dmp, SIGNAL, DT, **SETTINGS)
    for gain in (0.5, 1.0):
        retunes = _heard(gain)
        schedule = CanonicalSchedule.record(dmp, SIGNAL, DT, retunes=retunes, **SETTINGS)
        first = int(retunes.steps[0])
        np.testing.assert_array_equal(schedule.states[:first], plain.states[:first])   # nothing changes before it
        before = plain.states[first]
        for column in (3, 5):                               # the smoothed frequency and the oscillator's
            expected = before[column] + gain * (retunes.targets[0] - before[column])
            assert schedule.states[first, column] == pytest.approx(expected, rel=1e-12)
        assert schedule.retunes == retunes and schedule.matches(dmp, SIGNAL, DT, None, retunes, **SETTINGS)
        assert not schedule.matches(dmp, SIGNAL, DT, None, None, **SETTINGS)


@pytest.mark.parametrize("at", [0, 101, 162, 400, 799])
def test_a_resumed_schedule_keeps_the_recorded_corrections_bit_for_bit(dmp, at):
    retunes = _heard(0.8)                                   # 162 is a correction's own step
    schedule = CanonicalSchedule.record(dmp, SIGNAL, DT, retunes=retunes, **SETTINGS)
    resumed = schedule.resume(dmp, at, SIGNAL, **SETTINGS)
    np.testing.assert_array_equal(resumed.states, schedule.states)
    np.testing.assert_array_equal(resumed.rollout(dmp), schedule.rollout(dmp))
    without = schedule.resume(dmp, 400, SIGNAL, retunes=None, **SETTINGS)
    np.testing.assert_array_equal(without.states[:401], schedule.states[:401])
    assert without.retunes is None and not np.array_equal(without.states[450:], schedule.states[450:])


def test_corrections_follow_a_tempo_change_faster_and_keep_the_path_smooth(dmp):
    plain = CanonicalSchedule.record(dmp, SIGNAL, DT, **SETTINGS)
    heard = CanonicalSchedule.record(dmp, SIGNAL, DT, retunes=_heard(1.0), **SETTINGS)
    after = TIMES > 3.7
    target = 2 * np.pi * 1.3
    lag = {name: np.abs(schedule.states[:-1][after, 3] - target).mean() for name, schedule in (("plain", plain),
                                                                                              ("heard", heard))}
    assert lag["heard"] < 0.5 * lag["plain"]
    jerk = {name: np.abs(np.diff(schedule.rollout(dmp), 3, axis=0)).max()
            for name, schedule in (("plain", plain), ("heard", heard))}
    assert jerk["heard"] <= 1.5 * jerk["plain"]             # a correction moves the rate, not the path's acceleration


def test_bad_corrections_are_named():
    with pytest.raises(ValueError, match="steps"):
        Retunes(np.array([5, 3]), np.array([1.0, 1.0]), 0.5)
    with pytest.raises(ValueError, match="targets"):
        Retunes(np.array([3, 5]), np.array([1.0, -1.0]), 0.5)
    with pytest.raises(ValueError, match="gain"):
        Retunes(np.array([3, 5]), np.array([1.0, 1.0]), 0.0)
    with pytest.raises(TypeError, match="retunes"):
        CanonicalSchedule.record(DrumTask().imitation(), SIGNAL, DT, retunes={"steps": [1]}, **SETTINGS)
