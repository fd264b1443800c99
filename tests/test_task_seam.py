"""The task is a description: a third task (tap a marked point on the table, rhythmically) written in this file alone
runs on ARMAR-III, the Panda and a robot written in a test file; no file outside a task's folder names its objects or
info keys, and the agents name no task."""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar

import gymnasium as gym
import mujoco
import numpy as np
import pytest
import rdmp_gym.envs  # noqa: F401  (registers the ids)
from mini_arm import MINI
from rdmp_gym.envs.arena import FORCE, FOUND, NETFORCE, add_contact_sensor
from rdmp_gym.envs.registration import learner_defaults, register_task_ids, task_ids
from rdmp_gym.envs.rhythmic_env import RhythmicTaskEnv
from rdmp_gym.envs.rhythmic_step import RhythmicTaskStepEnv
from rdmp_gym.envs.step_book import StepBook
from rdmp_gym.envs.tasks import TASKS, Outcome, TaskDescription, TaskPlan, ToolPath, get_task, register_task

from rdmp_gym import Demonstration, RhythmicDMP

ROOT = Path(__file__).resolve().parent.parent

_POINTER = """
<mujoco model="pointer">
  <worldbody>
    <geom name="rod" type="capsule" fromto="0 0 0 -0.08 0 0" size="0.006" contype="6" conaffinity="1"/>
    <site name="point" pos="-0.086 0 0" size="0.003"/>
  </worldbody>
</mujoco>
"""


class TapTask(TaskDescription):
    """Tap a marked point on the table once per second with a pointer; success: at least 3 taps, all on the mark."""

    name = "Tap"
    groups = ("periodic", "transient", "amplitude")
    tool_site = "point"
    duration = 5.0

    def compose(self, spec: mujoco.MjSpec, robot, robot_prefix: str, tool_prefix: str) -> None:
        mount = robot.tool_mount
        frame = spec.body(robot_prefix + mount.body).add_frame(pos=list(mount.pos), quat=list(mount.quat))
        spec.attach(mujoco.MjSpec.from_string(_POINTER), frame=frame, prefix=tool_prefix)
        marker = spec.worldbody.add_body(name="marker", pos=[0.6, -0.28, 0.9])
        marker.add_geom(name="marker", type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[0.02, 0.001, 0], contype=0,
                        conaffinity=0, rgba=[0.9, 0.1, 0.1, 1])
        add_contact_sensor(spec, "tap", (mujoco.mjtObj.mjOBJ_GEOM, tool_prefix + "rod"),
                           (mujoco.mjtObj.mjOBJ_GEOM, "table_top"), FOUND | FORCE, NETFORCE)

    def imitation(self) -> RhythmicDMP:
        t = np.arange(0.0, 6.0, 0.01)
        come = np.clip(t / 1.0, 0, 1)[:, None] ** 2 * (3 - 2 * np.clip(t / 1.0, 0, 1)[:, None])
        tap = np.c_[np.zeros_like(t), np.zeros_like(t), 0.03 + 0.033 * np.cos(2 * np.pi * (t - 1.0))]
        return RhythmicDMP.fit(Demonstration(t, np.array([0.0, 0.05, 0.1]) + come * (tap - [0.0, 0.05, 0.1])),
                               n_periodic=10, n_transient=10)

    def context_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return np.array([0.0, -0.08]), np.array([0.08, 0.05])

    def sample_context(self, rng: np.random.Generator, options: Mapping[str, Any] | None) -> Any:
        low, high = self.context_bounds()
        point = np.asarray((options or {}).get("point", rng.uniform(low, high)), dtype=np.float64)
        return type("TapContext", (), {"point": point, "vector": lambda self: self.point})()

    def place(self, model: mujoco.MjModel, context: Any) -> None:
        table = model.body("table").pos
        model.body("marker").pos = table + np.r_[context.point, 0.0]

    def plan(self, dmp: RhythmicDMP, theta: np.ndarray, extras: np.ndarray, context: Any, times: np.ndarray,
             table_origin: np.ndarray) -> TaskPlan:
        path = dmp.with_params(theta, self.groups).rollout(times)
        return TaskPlan(path, table_origin + np.r_[context.point, 0.0], np.eye(3))

    def evaluate(self, path: ToolPath, context: Any, sensor: Mapping[str, slice]) -> Outcome:
        force = path.sensors[:, sensor["tap"]][:, 1:4] @ np.array([0.0, 0.0, 1.0])
        pressing = np.abs(force) > 0.5
        taps = int(np.sum(np.diff(pressing.astype(int)) == 1))
        cost = np.zeros(len(path.plan.path))
        cost[-1] = abs(taps - 4) / 4.0
        return Outcome({"taps": -float(cost[-1])}, cost, {"taps": taps}, () if taps >= 3 else ("taps",))


class EndAfter(StepBook):
    """The generic step interface, ended by the task after ``steps`` control steps and judged only then."""

    refused: ClassVar[Mapping[str, str]] = {"reward_every": "it judges the episode once, at its end"}

    def __init__(self, face: RhythmicTaskEnv, steps: int):
        super().__init__(face, reward_every=face.n_steps)
        self.steps = steps

    def ended(self, k: int) -> bool:
        return k + 1 >= self.steps


class ShortTap(TapTask):
    """The tap task with a step interface of its own: a step episode of 50 control steps."""

    def step_book(self, face: RhythmicTaskEnv, reward_every: int) -> StepBook:
        return EndAfter(face, 50)


@pytest.fixture(scope="module", autouse=True)
def tap_registered():
    register_task("tap", TapTask, id_name="Tap")
    yield register_task_ids("tap", robots=("armar3", "panda"))
    TASKS.pop("tap")


@pytest.mark.parametrize("robot", ["armar3", "panda", MINI])
def test_a_task_described_alone_runs_on_both_robots_and_a_robot_described_alone(robot):
    env = RhythmicTaskEnv("tap", robot)
    observation, _ = env.reset(seed=0)
    assert observation.shape == (2,)
    _, reward, terminated, truncated, info = env.step(np.zeros(env.action_space.shape, np.float32))
    assert terminated and not truncated and info["valid"], info["invalid_reason"]
    assert np.isclose(reward, -info["cost_trace"].sum())
    assert info["taps"] >= 3 and info["is_success"]


def test_a_registered_task_gets_episodic_and_step_ids_for_every_robot(tap_registered):
    assert tap_registered == ["rdmp_gym/ArmarTap-v1", "rdmp_gym/PandaTap-v1"]
    assert task_ids("tap", "panda", 1) == ("rdmp_gym/PandaTap-v1", "rdmp_gym/PandaTapStep-v1")
    env = gym.make("rdmp_gym/ArmarTapStep-v1")
    assert type(env.unwrapped) is RhythmicTaskStepEnv and type(env.unwrapped.book) is StepBook     # the generic twin
    env.reset(seed=1)
    total, done = 0.0, False
    while not done:
        _, reward, terminated, truncated, info = env.step(np.zeros(3))
        total, done = total + reward, terminated or truncated
    assert info["is_success"] and np.isclose(total, -info["cost_trace"].sum())


@pytest.mark.parametrize("env_id", ["rdmp_gym/ArmarWipeStep-v3", "rdmp_gym/PandaWipeStep-v3"])
def test_the_wiping_step_ids_are_the_generic_step_twin_of_the_task(env_id):
    spec = gym.spec(env_id)
    assert spec.entry_point == "rdmp_gym.envs.rhythmic_step:RhythmicTaskStepEnv" and spec.kwargs["task"] == "wipe"


def test_a_tasks_step_book_ends_an_episode_early_and_refuses_a_setting_by_name():
    env = RhythmicTaskStepEnv(task=ShortTap(), robot="armar3")
    env.reset(seed=1)
    rewards, done = [], False
    while not done:
        _, reward, terminated, truncated, info = env.step(np.zeros(3))
        rewards.append(reward)
        done = terminated or truncated
    assert len(rewards) == 50 and terminated and not truncated
    assert rewards[:-1] == [0.0] * 49 and rewards[-1] == info["episode_reward"] and "is_success" in info
    with pytest.raises(RuntimeError, match="ended"):
        env.step(np.zeros(3))
    with pytest.raises(ValueError, match="reward_every"):
        RhythmicTaskStepEnv(task=ShortTap(), robot="armar3", reward_every=2)


class OwnBook(StepBook):
    """A book of a task's own that keeps the generic judgement."""


class JudgedTap(TapTask):
    """The tap task with a book of its own, judged at the twin's resolution; it notes the steps it judged."""

    def __init__(self):
        super().__init__()
        self.judged: list[int] = []

    def step_book(self, face: RhythmicTaskEnv, reward_every: int) -> StepBook:
        return OwnBook(face, reward_every)

    def evaluate(self, record: ToolPath, context: Any, sensor: Mapping[str, slice]) -> Outcome:
        self.judged.append(record.steps)
        return super().evaluate(record, context, sensor)


def test_a_tasks_step_book_gets_the_twins_reward_resolution():
    task = JudgedTap()
    env = RhythmicTaskStepEnv(task=task, robot="armar3", reward_every=7)
    assert type(env.book) is OwnBook and env.book.reward_every == 7
    env.reset(seed=1)
    for _ in range(30):
        env.step(np.zeros(3))
    assert task.judged == [7, 14, 21, 28]


def test_tasks_are_refused_by_name():
    with pytest.raises(ValueError, match="task"):
        get_task("juggling")
    with pytest.raises(ValueError, match="version"):
        RhythmicTaskEnv("tap", "armar3", version=2)
    with pytest.raises(TypeError, match="factory"):
        register_task("bad", 3)


# ------------------------------------------------------------------ the seam holds
_DRUMMING = ROOT / "envs" / "tasks" / "drumming"
#: the drumming task's object names and info keys
_DRUM_WORDS = ("membrane", "drum_hit", "robot_rim", "robot_drum", "struck_fraction", "strike_impulses",
               "timing_error", "beat_times", "double_strikes")


def _python_files(*folders: str) -> list[Path]:
    return [path for folder in folders for path in (ROOT / folder).rglob("*.py")]


def test_no_file_outside_the_drumming_folder_names_its_objects_or_info_keys():
    pattern = re.compile("[\"'](" + "|".join(_DRUM_WORDS) + ")[\"']")
    found = [f"{path.relative_to(ROOT)}: {match.group(0)}" for path in _python_files("envs", "agents", "rdmp_gym")
             if _DRUMMING not in path.parents for match in pattern.finditer(path.read_text())]
    assert not found


def test_the_agents_name_no_env_id_and_read_task_defaults_from_the_env_registry():
    literal = re.compile(r"[\"']rdmp_gym/[A-Z]\w*-v\d+[\"']")
    found = [f"{path.relative_to(ROOT)}" for path in _python_files("agents") if literal.search(path.read_text())]
    assert not found
    assert learner_defaults("rdmp_gym/ArmarWipe-v2")["cpi2"]["gain_groups"][-2:] == ["sweep_x", "sweep_y"]
    assert learner_defaults("rdmp_gym/ArmarWipeStep-v2") == {}
    assert learner_defaults("rdmp_gym/ArmarDrum-v1") == {}                  # no drumming-specific structure
    assert learner_defaults("CartPole-v1") == {}


# ------------------------------------------------------------------ the wiping task is a description too
_WIPING = ROOT / "envs" / "tasks" / "wiping"
#: the wiping task's objects (the sponge tool, its sensors, the cup) and its own info keys; keys every task's info may
#: hold (the steps, the path's smoothness, a force trace) are not the wiping task's
_WIPE_OBJECTS = ("sponge", "sponge_tcp", "sponge_touch", "sponge_table", "wrist_force", "wrist_torque", "obstacle",
                 "arm_obstacle")
_SHARED_KEYS = {"steps", "jerk_ratio", "peak_joint_accel", "force_trace"}


def _wipe_words() -> tuple[str, ...]:
    from rdmp_gym.envs.tasks.wiping.info import SCALAR_STATISTICS, TRACE_STATISTICS

    keys = {*SCALAR_STATISTICS, *TRACE_STATISTICS, "cost_terms", "n_cells", "clearance_push", "simulated_coverage",
            "fine_force_trace", "episode_reward_terms"} - _SHARED_KEYS
    return (*_WIPE_OBJECTS, *sorted(keys))


def test_no_file_of_the_envs_outside_the_wiping_folder_names_its_objects_or_info_keys():
    pattern = re.compile("[\"'](" + "|".join(_wipe_words()) + ")[\"']")
    found = [f"{path.relative_to(ROOT)}: {match.group(0)}" for path in _python_files("envs")
             if _WIPING not in path.parents for match in pattern.finditer(path.read_text())]
    assert not found


def test_the_wiping_task_is_a_registered_description_that_serves_its_published_ids():
    from rdmp_gym.envs.tasks.wiping.env import ArmarWipeEnv
    from rdmp_gym.envs.tasks.wiping.faces import EPISODIC, LEGACY_STEP, STEP
    from rdmp_gym.envs.tasks.wiping.task import WipingTask

    entry = TASKS["wipe"]
    assert entry.versions == (1, 2, 3) and entry._factory() is WipingTask and issubclass(WipingTask, TaskDescription)
    assert EPISODIC == "rdmp_gym.envs.rhythmic_env:RhythmicTaskEnv"
    for robot, version, step in (("armar3", 1, LEGACY_STEP), ("armar3", 2, LEGACY_STEP), ("armar3", 3, STEP),
                                 ("panda", 3, STEP)):
        episodic_id, step_id = task_ids("wipe", robot, version)
        assert gym.spec(episodic_id).entry_point == EPISODIC and gym.spec(step_id).entry_point == step
        assert gym.spec(episodic_id).kwargs["task"] == "wipe"
    assert entry.face_specs("panda", 2) is None and "rdmp_gym/PandaWipe-v2" not in gym.registry
    assert learner_defaults("rdmp_gym/PandaWipe-v3") == entry.learner_defaults(3) != {}
    assert issubclass(ArmarWipeEnv, RhythmicTaskEnv)


@pytest.mark.parametrize("robot", ["armar3", "panda"])
def test_the_wiping_ids_are_made_by_the_generic_face(robot):
    """``gym.make`` of a wiping id, ``RhythmicTaskEnv("wipe", ...)`` and the kept name ``ArmarWipeEnv`` make the same
    episodic face and the same episode."""
    from rdmp_gym.envs.tasks.wiping.env import ArmarWipeEnv

    made = gym.make(task_ids("wipe", robot, 3)[0]).unwrapped
    direct = RhythmicTaskEnv("wipe", robot, version=3, obstacle=True)
    kept = ArmarWipeEnv(robot=robot, version=3, obstacle=True)
    assert type(made) is RhythmicTaskEnv and type(direct) is RhythmicTaskEnv and isinstance(kept, RhythmicTaskEnv)
    action = 0.3 * np.random.default_rng(0).uniform(-1, 1, made.action_space.shape).astype(np.float32)
    results = []
    for env in (made, direct, kept):
        observation, _ = env.reset(seed=5)
        _, reward, *_, info = env.step(action)
        results.append((observation, reward, info["coverage"], info["is_success"]))
        assert env.task.task_version.version == 3 and not hasattr(env, "task_version")       # no forwarding
        with pytest.raises(AttributeError, match=r"fine_force.*env\.unwrapped\.task\.fine_force"):
            env.fine_force = True                     # a setting of the task is not silently kept on the face
    for other in results[1:]:
        assert np.array_equal(other[0], results[0][0]) and other[1:] == results[0][1:]


def test_the_wiping_env_reads_its_task_from_the_description():
    env = gym.make("rdmp_gym/ArmarWipe-v3").unwrapped
    task = env.task
    observation, _ = env.reset(seed=3)
    assert task.name == "Wipe" and task.version == 3 and task.imitation() is env.dmp
    low, high = task.context_bounds()
    assert observation.shape == low.shape and np.all(observation >= low - 1e-6) and np.all(observation <= high + 1e-6)
    plan = task.plan(env.dmp, env.action_map.theta0, np.zeros(0), env.context, env.times, env.scene.table_origin)
    assert np.array_equal(plan.path, env.rollout_path(env.action_map.theta0))
    _, reward, *_, info = env.step(np.zeros(env.action_space.shape, np.float32))
    assert np.isclose(reward, -info["cost_trace"].sum()) and info["valid"]
