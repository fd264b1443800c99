"""One set of defaults: the library's, the config objects', the CLI's and the main job's agree (the main learner on
the current task), and the env's settings are validated once, with errors that name the setting."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import pytest
from rdmp_gym.agents.run_commands import parse_main, parse_train, train_config
from rdmp_gym.agents.tasks import (
    MAIN_AGENT,
    MAIN_ENV,
    MAIN_ENV_KWARGS,
    MAIN_OPTIONS,
    STEP_AGENT,
    STEP_OPTIONS,
    TaskSpec,
    main_agent,
)
from rdmp_gym.agents.training import TrainConfig
from rdmp_gym.envs import LATEST_ENV_ID
from rdmp_gym.envs.registration import env_settings
from rdmp_gym.envs.tasks.wiping.settings import EnvConfig, SettingTypeError

_TASK = ("agent", "env_id", "env_kwargs", "options", "start", "perturbation", "seed", "shared_context")


def _task_fields(config: TrainConfig) -> dict:
    return {name: getattr(config, name) for name in _TASK}


def test_train_config_default_is_the_main_learner_on_the_current_task():
    config = TrainConfig()
    assert (config.agent, config.env_id) == (MAIN_AGENT, MAIN_ENV) == ("bbrl", LATEST_ENV_ID)
    assert dict(config.env_kwargs) == MAIN_ENV_KWARGS
    assert config.options.sigma_factors == MAIN_OPTIONS["sigma_factors"]
    assert TaskSpec() == TaskSpec(MAIN_ENV, MAIN_ENV_KWARGS)


def test_the_cli_and_the_main_job_start_from_the_same_defaults(tmp_path):
    library = TrainConfig()
    train = train_config(parse_train(["--out", str(tmp_path / "a")]))
    main = train_config(parse_main([]))
    assert _task_fields(train) == _task_fields(library) == _task_fields(main)
    assert (train.updates, train.rollouts, train.eval_episodes, train.eval_every) == \
        (library.updates, library.rollouts, library.eval_episodes, library.eval_every)


def test_main_keywords_and_options_only_apply_to_the_main_env_and_learner():
    other = TrainConfig(env_id="rdmp_gym/ArmarWipe-v2")
    assert dict(other.env_kwargs) == {} and other.options.sigma_factors == {}
    cmaes = TrainConfig(agent="cmaes")
    assert dict(cmaes.env_kwargs) == MAIN_ENV_KWARGS
    assert dict(TrainConfig(env_kwargs={}).env_kwargs) == {}                 # given keywords are used as given


def test_a_step_based_env_gets_the_step_learner_in_every_layer(tmp_path):
    step_env = "InvertedPendulum-v5"
    assert (main_agent(step_env), main_agent(MAIN_ENV), main_agent("rdmp_gym/PandaDrum-v1")) == \
        (STEP_AGENT, MAIN_AGENT, MAIN_AGENT) == ("cmaes", "bbrl", "bbrl")
    library = TrainConfig(env_id=step_env)
    assert library.agent == "cmaes" and library.options.sigma == STEP_OPTIONS["sigma"] == 0.2
    assert TrainConfig.from_dict({"env_id": step_env}).agent == "cmaes"
    assert TrainConfig(env_id=step_env, agent="cmaes", options={"sigma": 0.6}).options.sigma == 0.6
    assert TrainConfig(env_id=MAIN_ENV, agent="cmaes").options.sigma == 0.6        # CMA-ES's own on a task
    command = train_config(parse_train(["--env", step_env, "--out", str(tmp_path / "a")]))
    assert _task_fields(command) == _task_fields(library)
    parsed = parse_train(["--env", step_env, "--options.sigma", "0.4", "--out", str(tmp_path / "b")])
    wider = train_config(parsed, parsed.options)
    assert (wider.agent, wider.options.sigma) == ("cmaes", 0.4)
    assert train_config(parse_train(["--env", step_env, "--agent", "bbrl", "--out", str(tmp_path / "c")])).agent \
        == "bbrl"


def test_the_wiping_env_defaults_to_the_current_version():
    assert EnvConfig().task.version == gym.spec(LATEST_ENV_ID).kwargs["version"] == 3
    assert env_settings("rdmp_gym/ArmarWipe-v1").task.version == 1              # every id names its version
    assert env_settings("rdmp_gym/ArmarWipe-v2").task.version == 2
    assert env_settings("rdmp_gym/ArmarWipeStep-v1")["version"] == 1


def test_a_task_built_by_name_is_its_latest_version_with_its_learner_defaults():
    from rdmp_gym.envs.registration import learner_defaults
    from rdmp_gym.envs.rhythmic_env import RhythmicTaskEnv
    from rdmp_gym.envs.tasks import TASKS

    env = RhythmicTaskEnv("wipe")
    assert env.version == max(TASKS["wipe"].versions) == 3
    assert TASKS["wipe"].learner_defaults() == learner_defaults(LATEST_ENV_ID) != learner_defaults(
        "rdmp_gym/ArmarWipe-v1")
    env.close()


@pytest.mark.parametrize(("env_id", "kwargs", "error", "name"), [
    ("rdmp_gym/ArmarWipe-v3", {"target_forse": 10.0}, SettingTypeError, "target_forse"),
    ("rdmp_gym/ArmarWipe-v3", {"target_force": -1.0}, ValueError, "target_force"),
    ("rdmp_gym/ArmarDrum-v1", {"tolerence": 0.05}, TypeError, "tolerence"),
    ("rdmp_gym/ArmarDrum-v1", {"tolerance": -1.0}, ValueError, "tolerance"),
    ("rdmp_gym/DMPTracking-v0", {"nonsense": 1}, TypeError, "nonsense"),
    ("rdmp_gym/ArmarWipe-v9", {}, ValueError, "env_id"),
])
def test_a_run_with_a_bad_env_setting_is_refused_when_it_is_configured(env_id, kwargs, error, name):
    with pytest.raises(error, match=name):
        TrainConfig(agent="cmaes", env_id=env_id, env_kwargs=kwargs)


def test_the_run_carries_the_envs_typed_settings():
    config = TrainConfig(env_kwargs={"target_force": 12.0})
    settings = config.env_settings
    assert isinstance(settings, EnvConfig)
    assert settings.force.target_force == 12.0 and settings.task.version == 3
    drum = TrainConfig(agent="cmaes", env_id="rdmp_gym/PandaDrum-v1", env_kwargs={"tolerance": 0.04})
    assert drum.env_settings == {"task": "drum", "robot": "panda", "version": 1, "tolerance": 0.04}
    assert dataclasses.replace(config, seed=1).env_settings == settings


def test_the_input_checks_have_one_home():
    """``rdmp_gym.validation`` defines every check; no module of the core, the envs or the agents defines its own."""
    import ast
    from pathlib import Path

    import rdmp_gym.validation as validation

    root = Path(__file__).resolve().parent.parent
    homes = {}
    for folder in ("rdmp_gym", "envs", "agents"):
        for path in sorted((root / folder).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, (ast.FunctionDef, ast.ClassDef)) and node.name.lstrip("_") in validation.__all__:
                    homes.setdefault(node.name.lstrip("_"), []).append(str(path.relative_to(root)))
    shared = "rdmp_gym/validation.py"
    assert homes and all(files == [shared] for files in homes.values()), homes
    assert SettingTypeError is validation.SettingTypeError
    with pytest.raises(ValueError, match="rollouts"):
        TrainConfig(rollouts=1)                                 # the agents' range check, from the same home
    with pytest.raises(SettingTypeError, match="target_force"):
        EnvConfig.from_kwargs(target_force="strong")            # the envs' number check, from the same home
