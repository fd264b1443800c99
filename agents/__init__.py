"""rdmp_gym.agents: imitation initialisation, PI²/PI^BB/CMA-ES learners, SB3 baselines, runs and the CLI."""
