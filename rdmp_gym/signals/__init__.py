"""Sampled motion and its analysis, without a DMP: the bottom layer of the core above :mod:`rdmp_gym.validation`.

* :mod:`~rdmp_gym.signals.demonstrations`: the :class:`~rdmp_gym.signals.demonstrations.Demonstration` container,
  its files and a recorder's samples on an even grid;
* :mod:`~rdmp_gym.signals.filters`: outliers and smoothed derivatives of sampled signals;
* :mod:`~rdmp_gym.signals.segmentation`: where the periodic part of a demonstration or a recording starts and ends,
  its period, the rests around it and the sessions of a recording.
"""
