"""The drumming task's re-plan: a plan of other weights in the same context with the same extras follows the canonical
schedule recorded by the first plan (rdmp_gym.dmp.frequency.CanonicalSchedule), and equals the stepper's path bit for
bit."""

import numpy as np
import pytest
from rdmp_gym.envs.tasks.drumming.task import DrumTask

from rdmp_gym.dmp.frequency import AdaptiveFrequencyStepper, CanonicalSchedule

TIMES = np.arange(1000) * 0.01
ORIGIN = np.zeros(3)


@pytest.fixture(scope="module")
def drum():
    task = DrumTask()
    dmp = task.imitation()
    return task, dmp, dmp.get_params(task.groups), task.sample_context(np.random.default_rng(11), None)


def stepped_path(task, dmp, theta, extras, context):
    """The plan's path as the stepper runs it online, one control step at a time (the reference)."""
    coupling, phase_gain, shift = extras
    metronome = task.metronome(context)
    beats, _ = task.beats(metronome)
    stepper = AdaptiveFrequencyStepper(dmp.with_params(theta, task.groups), TIMES[1] - TIMES[0],
                                       coupling=2.0 * 4.0**coupling, phase_gain=2.0 * 4.0**phase_gain,
                                       frequency=metronome.omega)
    signal = metronome.signal(TIMES, shift=shift)
    stop_at = task.stop_request(metronome, beats[-1])
    path = np.empty((TIMES.size, 3))
    for k, t in enumerate(TIMES):
        if t >= stop_at and stepper.stop is None:
            stepper.request_stop()
        path[k] = stepper.y
        stepper.step(signal[k])
    assert stepper.stop is not None                     # the stop's part of the path is compared too
    return path


def test_a_plan_of_new_weights_replays_the_schedule_and_is_the_stepped_plan(drum):
    task, dmp, theta, context = drum
    extras = np.array([0.3, -0.4, 0.1])
    first = task.plan(dmp, theta, extras, context, TIMES, ORIGIN).path
    schedule = task._last_schedule
    rng = np.random.default_rng(3)
    for _ in range(3):
        changed = theta + 0.05 * rng.standard_normal(theta.size)      # every group: weights, amplitude, stop
        path = task.plan(dmp, changed, extras, context, TIMES, ORIGIN).path
        assert task._last_schedule is schedule                        # replayed, not recorded again
        np.testing.assert_array_equal(path, stepped_path(task, dmp, changed, extras, context))
        assert np.abs(path - first).max() > 1e-3


@pytest.mark.parametrize("which", [0, 1, 2])
def test_a_change_of_extras_records_a_new_schedule(drum, which):
    task, dmp, theta, context = drum
    extras = np.array([0.3, -0.4, 0.1])
    first = task.plan(dmp, theta, extras, context, TIMES, ORIGIN).path
    schedule = task._last_schedule
    extras[which] += 0.2
    path = task.plan(dmp, theta, extras, context, TIMES, ORIGIN).path
    assert task._last_schedule is not schedule
    np.testing.assert_array_equal(path, stepped_path(task, dmp, theta, extras, context))
    assert np.abs(path - first).max() > 1e-4


def test_a_change_of_context_records_a_new_schedule(drum):
    task, dmp, theta, context = drum
    extras = np.zeros(3)
    task.plan(dmp, theta, extras, context, TIMES, ORIGIN)
    other = task.sample_context(np.random.default_rng(12), None)
    path = task.plan(dmp, theta, extras, other, TIMES, ORIGIN).path
    np.testing.assert_array_equal(path, stepped_path(task, dmp, theta, extras, other))


def test_a_schedule_refuses_another_canonical_system_and_a_bad_stop_step(drum):
    task, dmp, _, context = drum
    signal = task.metronome(context).signal(TIMES[:50])
    schedule = CanonicalSchedule.record(dmp, signal, 0.01, 20)
    moved = dmp.with_params(dmp.get_params("initial:0") + np.array([0.2, 0.0]), "initial:0")   # another start phase
    assert schedule.matches(dmp, signal, 0.01, 20)
    assert not schedule.matches(moved, signal, 0.01, 20)
    assert not schedule.matches(dmp, signal, 0.01, 20, coupling=3.0)
    with pytest.raises(ValueError, match="dmp"):
        schedule.rollout(moved)
    with pytest.raises(ValueError, match="stop_step"):
        CanonicalSchedule.record(dmp, signal, 0.01, 50)
