"""The DMP itself: its formulation, the DMPs built on it, their fit to demonstrations and their files.

Imports :mod:`rdmp_gym.signals` and :mod:`rdmp_gym.validation` only.

* the formulation (Ernesti et al. 2012): :mod:`~rdmp_gym.dmp.canonical` (the canonical system),
  :mod:`~rdmp_gym.dmp.basis` (basis functions and fades), :mod:`~rdmp_gym.dmp.transformation` (the transformation
  system), :mod:`~rdmp_gym.dmp.start` (the transient start), :mod:`~rdmp_gym.dmp.ending` (the stop),
  :mod:`~rdmp_gym.dmp.batched` (the forcing term of many rollouts);
* the DMPs: :mod:`~rdmp_gym.dmp.rhythmic` (:class:`~rdmp_gym.dmp.rhythmic.RhythmicDMP`, its rollout and
  stepper), :mod:`~rdmp_gym.dmp.classic` (the classic periodic DMP), :mod:`~rdmp_gym.dmp.pose` with
  :mod:`~rdmp_gym.dmp.quaternion` (position and orientation);
* beyond the paper: :mod:`~rdmp_gym.dmp.sweep` (the anchor's travel), :mod:`~rdmp_gym.dmp.coupling` (obstacle
  avoidance), :mod:`~rdmp_gym.dmp.frequency` (following an external rhythm);
* the fit to a demonstration: :mod:`~rdmp_gym.dmp.settings`, :mod:`~rdmp_gym.dmp.fitting` (behind
  :meth:`RhythmicDMP.fit <rdmp_gym.dmp.rhythmic.RhythmicDMP.fit>`), :mod:`~rdmp_gym.dmp.stopping` (the stop's fit);
* what a learner and a file see of a DMP: :mod:`~rdmp_gym.dmp.parameters`, :mod:`~rdmp_gym.dmp.serialization`.
"""
