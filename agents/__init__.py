"""rdmp_gym.agents: imitation start, PI²/PI^BB/CMA-ES learners, SB3 PPO, training runs and the CLI.

Main entry points (stable-baselines3/torch are imported only when PPO is used)::

    from rdmp_gym.agents import TrainConfig, train, evaluate_run
    run = train(TrainConfig(agent="pi2", updates=30, rollouts=10, workers=2), "runs/pi2", progress=True)
    evaluate_run(run.path, episodes=10)
"""

from .assessment import evaluate_run, record_best_episode
from .evaluation import Evaluator
from .imitation import fit_dmp, load_demonstration
from .learners import CMAES, PI2, PIBB, CMAESConfig, EpisodeBatch, Learner, PI2Config, PIBBConfig, make_learner
from .ppo_config import PPOConfig
from .runs import RunDirectory
from .tasks import WIPE_ID, TaskSpec
from .tracking import TRACKING_ID, TrackingEnv
from .training import AGENTS, TrainConfig, train

__all__ = ["AGENTS", "CMAES", "PI2", "PIBB", "TRACKING_ID", "WIPE_ID", "CMAESConfig", "EpisodeBatch", "Evaluator",
           "Learner", "PI2Config", "PIBBConfig", "PPOConfig", "RunDirectory", "TaskSpec", "TrackingEnv",
           "TrainConfig", "evaluate_run", "fit_dmp", "load_demonstration", "make_learner", "record_best_episode",
           "train"]
