"""The published versions 1 and 2 of the wiping task, frozen so that their numbers reproduce bit for bit.

- :mod:`~rdmp_gym.envs.tasks.wiping.legacy.task`: :class:`~.task.LegacyWipingTask`, the description of the versions 1
  and 2 (the robot's hand-merged scene, the pattern in place of version 1, their cup placement, smoothness and
  success criteria) on the generic episodic face;
- :mod:`~rdmp_gym.envs.tasks.wiping.legacy.step`: their step env (``rdmp_gym/ArmarWipeStep-v1``, ``-v2``), which
  runs the DMP online;
- :mod:`~rdmp_gym.envs.tasks.wiping.legacy.env`: the deprecated id ``rdmp_gym/ArmarWipe-v0``.
"""
