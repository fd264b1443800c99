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


def recorded(task, dmp, theta, extras, context):
    """The schedule and settings of a plan of ``extras`` in ``context`` (recorded afresh)."""
    plan = task.plan(dmp, theta, extras, context, TIMES, ORIGIN)
    settings, signal = task._rhythm(extras, task.metronome(context), TIMES)
    return plan, settings, signal


@pytest.mark.parametrize("step", [0, 1, 333, TIMES.size])
def test_resuming_a_schedule_with_its_own_settings_is_the_schedule_bit_for_bit(drum, step):
    task, dmp, theta, context = drum
    plan, settings, signal = recorded(task, dmp, theta, np.array([0.3, -0.4, 0.1]), context)
    schedule = plan.extras["schedule"]
    resumed = schedule.resume(dmp, step, signal, **settings)
    for mine, theirs in [(resumed.s, schedule.s), (resumed.ds, schedule.ds), (resumed.states, schedule.states),
                         *zip(resumed.hold, schedule.hold, strict=True)]:
        np.testing.assert_array_equal(mine, theirs)
    assert resumed.since == step
    assert resumed.matches(dmp, signal, 0.01, schedule.stop_step, **settings) == (step == 0)   # no record's but one


def test_resuming_at_the_start_with_other_settings_is_their_record(drum):
    task, dmp, theta, context = drum
    plan, _, _ = recorded(task, dmp, theta, np.array([0.3, -0.4, 0.1]), context)
    other, other_settings, other_signal = recorded(task, dmp, theta, np.array([0.6, 0.0, -0.2]), context)
    resumed = plan.extras["schedule"].resume(dmp, 0, other_signal, **other_settings)
    np.testing.assert_array_equal(resumed.states, other.extras["schedule"].states)
    np.testing.assert_array_equal(resumed.rollout(dmp)[:-1], other.path)


@pytest.mark.parametrize("which", [0, 1, 2])
def test_a_resumed_schedule_keeps_the_past_and_goes_on_from_its_state(drum, which):
    """Gains or the shift changed at step 400: the canonical time and its rate before it are the running
    schedule's, the rate goes on from where it was (no jump of the phase), and it differs afterwards."""
    task, dmp, theta, context = drum
    extras = np.array([0.3, -0.4, 0.1])
    plan, _, _ = recorded(task, dmp, theta, extras, context)
    extras[which] += 0.3
    live = plan.extras["schedule"]
    resumed = task.resume_plan(plan, 400, dmp, theta, extras, context, TIMES, ORIGIN).extras["schedule"]
    np.testing.assert_array_equal(resumed.s[:401], live.s[:401])
    np.testing.assert_array_equal(resumed.states[:401], live.states[:401])
    assert not np.array_equal(resumed.s[450:], live.s[450:])
    replayed = task.plan(dmp, theta, extras, context, TIMES, ORIGIN).extras["schedule"]
    assert abs(replayed.s[400] - live.s[400]) > 1e-4                 # a replay from the start jumps the phase


def test_resume_plan_with_the_running_settings_reuses_the_schedule(drum):
    task, dmp, theta, context = drum
    extras = np.array([0.3, -0.4, 0.1])
    plan = task.plan(dmp, theta, extras, context, TIMES, ORIGIN)
    changed = theta + 0.05 * np.random.default_rng(4).standard_normal(theta.size)
    resumed = task.resume_plan(plan, 400, dmp, changed, extras, context, TIMES, ORIGIN)
    assert resumed.extras["schedule"] is plan.extras["schedule"]
    np.testing.assert_array_equal(resumed.path, task.plan(dmp, changed, extras, context, TIMES, ORIGIN).path)


def test_resume_refuses_bad_input(drum):
    task, dmp, theta, context = drum
    plan, settings, signal = recorded(task, dmp, theta, np.zeros(3), context)
    schedule = plan.extras["schedule"]
    with pytest.raises(ValueError, match="step"):
        schedule.resume(dmp, TIMES.size + 1, signal, **settings)
    with pytest.raises(ValueError, match="u"):
        schedule.resume(dmp, 10, signal[:-1], **settings)
    with pytest.raises(ValueError, match="frequency"):
        schedule.resume(dmp, 10, signal, **{**settings, "frequency": 2.0 * settings["frequency"]})
    moved = dmp.with_params(dmp.get_params("initial:0") + np.array([0.2, 0.0]), "initial:0")
    with pytest.raises(ValueError, match="dmp"):
        schedule.resume(moved, 10, signal, **settings)


def test_a_retuned_schedule_follows_the_new_frequency_from_its_step(drum):
    task, dmp, theta, context = drum
    plan, settings, signal = recorded(task, dmp, theta, np.zeros(3), context)
    schedule = plan.extras["schedule"]
    faster = 1.2 * settings["frequency"]
    retuned = schedule.resume(dmp, 300, signal, retune=faster, **settings)
    np.testing.assert_array_equal(retuned.s[:301], schedule.s[:301])
    assert retuned.states[300, 3] == retuned.states[300, 5] == faster            # smoothed and oscillator frequency
    assert retuned.s[400] - retuned.s[300] > schedule.s[400] - schedule.s[300]   # the DMP runs faster after it
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError, match="retune"):
            schedule.resume(dmp, 300, signal, retune=bad, **settings)
