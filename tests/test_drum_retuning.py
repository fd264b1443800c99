"""The drumming task's version 2 (``rdmp_gym.envs.tasks.drumming.retuning``): its tempo value retunes the rhythm
follower, its cycle observation hears the tempo, and its action 0 plays as version 1's."""

import gymnasium as gym
import numpy as np
import pytest
import rdmp_gym.envs  # noqa: F401  (registers the ids)
from gymnasium.utils.env_checker import check_env
from rdmp_gym.envs.tasks import get_task
from rdmp_gym.envs.tasks.drumming import DrumTask
from rdmp_gym.envs.tasks.drumming.retuning import HEARING, RetuningDrumTask

SEED = 3


@pytest.fixture(scope="module")
def cycle_v2():
    env = gym.make("rdmp_gym/PandaDrumCycle-v2").unwrapped
    yield env
    env.close()


def _play(env, actions) -> tuple[float, list[np.ndarray]]:
    """Reset ``env`` (a cycle face) to :data:`SEED` and play ``actions(cycle, observation)``; the return and the
    observations at the cycles' starts."""
    observation, _ = env.reset(seed=SEED)
    seen = [observation]
    for cycle in range(env.n_cycles):
        observation, reward, terminated, _, _ = env.step(actions(cycle, observation))
        seen.append(observation)
        if terminated:
            return reward, seen
    raise AssertionError("the episode did not end")


def test_the_versions_build_their_descriptions_and_a_bad_version_is_named():
    assert type(get_task("drum")) is RetuningDrumTask and type(get_task("drum", version=1)) is DrumTask
    assert list(RetuningDrumTask.extras) == [*DrumTask.extras, "ear", "tempo"]
    with pytest.raises(ValueError, match="version"):
        get_task("drum", version=3)
    for robot in ("Armar", "Panda"):
        for version in (1, 2):
            assert f"rdmp_gym/{robot}DrumCycle-v{version}" in gym.registry


def test_the_action_0_plays_as_version_1_on_both_faces(cycle_v2):
    episodic = {version: gym.make(f"rdmp_gym/PandaDrum-v{version}") for version in (1, 2)}
    returns = {}
    for version, env in episodic.items():
        env.reset(seed=SEED)
        returns[version] = env.step(np.zeros(env.action_space.shape))[1]
        env.close()
    zero = np.zeros(cycle_v2.action_space.shape)
    cycle_return, _ = _play(cycle_v2, lambda cycle, observation: zero)
    assert returns[1] == returns[2] == cycle_return


def test_the_plans_tempo_value_starts_the_follower_at_its_frequency():
    env = gym.make("rdmp_gym/PandaDrum-v2").unwrapped
    env.reset(seed=SEED)
    action = np.zeros(env.action_space.shape)
    action[env.action_slices()["tempo"]] = -0.5
    env.step(action)
    schedule = env.solution.plan.extras["schedule"]
    announced = env.task.metronome(env.context).omega
    assert schedule.settings["frequency"] == pytest.approx(announced * 2.0 ** -0.25)
    assert env.solution.plan.extras["tempo"] == -0.5
    env.close()


def test_the_ear_takes_the_heard_tempo_a_beat_after_a_change_and_strikes_on_the_new_tempo():
    """At gain 1 the follower's frequency is the new tempo's from the first beat after the change plus the hearing
    span; the imitation's rhythm then keeps time through a large tempo fall where version 1's follower does not."""
    env = gym.make("rdmp_gym/PandaDrum-v2").unwrapped
    options = {"tempo": 110.0, "new_tempo": 90.0, "change_time": 4.0}
    errors = {}
    for gain in (0.0, 1.0):
        env.reset(seed=SEED, options=options)
        action = np.zeros(env.action_space.shape)
        action[env.action_slices()["ear"]] = gain
        info = env.step(action)[4]
        errors[gain] = info["mean_abs_timing_error"]
    schedule = env.solution.plan.extras["schedule"]
    metronome = env.task.metronome(env.context)
    after = np.searchsorted(env.times, metronome.change_time + HEARING)
    assert after in schedule.retunes.steps and schedule.retunes.gain == 1.0
    assert schedule.states[after, 5] == pytest.approx(2.0 * np.pi * 90.0 / 60.0)
    assert errors[1.0] < 0.5 * errors[0.0]
    env.close()


def test_a_cycle_that_changes_the_tempo_value_retunes_the_follower_from_its_start(cycle_v2):
    def retune_at_4(cycle, observation):
        action = np.zeros(cycle_v2.action_space.shape)
        action[-1] = 0.0 if cycle < 4 else 0.4
        return action

    _play(cycle_v2, retune_at_4)
    schedule = cycle_v2._plan.extras["schedule"]
    step = int(cycle_v2.start_steps[4])
    announced = cycle_v2.task.metronome(cycle_v2.face.context).omega
    assert schedule.since == step and schedule.states[step, 5] == pytest.approx(announced * 2.0**0.2)
    assert cycle_v2._plan.extras["tempo"] == 0.4


def test_a_cycle_after_the_stops_request_changes_nothing(cycle_v2):
    """Version 1 lets the last cycle move the stopped stick's rest (and fail the rest at the end); version 2 keeps
    the running plan once the stop is requested."""
    zero = np.zeros(cycle_v2.action_space.shape)
    amplitude = cycle_v2.face.action_slices()["amplitude"]
    zero_return, _ = _play(cycle_v2, lambda cycle, observation: zero)
    stop_at = cycle_v2.face.solution.plan.extras["stop_at"]
    late = int(np.flatnonzero(cycle_v2.starts > stop_at)[0])

    def late_change(cycle, observation):
        action = zero.copy()
        action[amplitude] = 0.3 if cycle >= late else 0.0
        return action

    late_return, _ = _play(cycle_v2, late_change)
    assert late_return == zero_return and cycle_v2._plan is cycle_v2.face.solution.plan


def test_the_heard_tempo_is_0_before_the_change_and_the_new_tempos_after_it(cycle_v2):
    zero = np.zeros(cycle_v2.action_space.shape)
    _, seen = _play(cycle_v2, lambda cycle, observation: zero)
    context = cycle_v2.face.context
    change = cycle_v2.task.metronome(context).change_time               # the beat nearest the context's time
    starts = np.r_[cycle_v2.starts, np.inf]
    heard = np.array([observation[-2] for observation in seen])
    before, after = starts <= change, starts >= change + HEARING
    assert before.any() and after[:-1].any()
    np.testing.assert_allclose(heard[before], 0.0, atol=1e-12)
    np.testing.assert_allclose(heard[after[: len(heard)]][:-1], np.log2(context.new_tempo / context.tempo),
                               rtol=1e-6)
    low, high = cycle_v2.observation_space.low, cycle_v2.observation_space.high
    assert all(np.all((low <= o) & (o <= high)) for o in seen)


def test_retuning_by_ear_beats_the_follower_alone_on_a_tempo_change(cycle_v2):
    """The tempo value set from the heard tempo in every cycle strikes closer to the beats than the follower's own
    adaptation, in a context with a large tempo fall."""
    options = {"tempo": 110.0, "new_tempo": 90.0, "change_time": 4.0}
    errors = {}
    for name, gain in (("alone", 0.0), ("by ear", 2.0)):
        observation, _ = cycle_v2.reset(seed=SEED, options=options)
        for _ in range(cycle_v2.n_cycles):
            action = np.zeros(cycle_v2.action_space.shape)
            action[-1] = gain * observation[-2]
            observation, _, terminated, _, info = cycle_v2.step(action)
            if terminated:
                break
        errors[name] = info["mean_abs_timing_error"]
    assert errors["by ear"] < 0.5 * errors["alone"]


def test_the_gymnasium_checker_passes_on_the_version_2_cycle_face():
    env = gym.make("rdmp_gym/PandaDrumCycle-v2")
    check_env(env.unwrapped, skip_render_check=True)
    env.close()
