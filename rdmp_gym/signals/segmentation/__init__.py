"""Segmentation: where the periodic part of sampled motion starts and ends, its period, and the rests around it.

One module per kind of input:

* :mod:`~rdmp_gym.signals.segmentation.demonstration`: a composed-periodic demonstration (Ernesti et al. 2012, IV and
  V-A), a transient start followed by periodic motion: period, transient length and anchor (:func:`segment`,
  :class:`Segmentation`), and the phase shift between two demonstrations (:func:`phase_shift`).
* :mod:`~rdmp_gym.signals.segmentation.recording`: a whole recording of a person (rest, approach, a rhythm whose working
  point drifts, departure, rest): :func:`segment_rhythm`, :class:`RhythmSegmentation`.
* :mod:`~rdmp_gym.signals.segmentation.ending`: a demonstration that ends (start, periodic part, stop, rest):
  :func:`segment_ending`, :class:`StopSegmentation`.

and the parts they share:

* :mod:`~rdmp_gym.signals.segmentation.period`: the one period estimator, :func:`estimate_period` (method
  ``"autocorrelation"`` for a demonstration whose last half is periodic, ``"local_fit"`` for a rhythm that runs
  for part of a recording under a large slow motion), and :func:`refine_period` (the period that fits a Fourier
  series best).
* :mod:`~rdmp_gym.signals.segmentation.fourier`: least-squares Fourier fits: the periodic template, its noise-scaled
  residual and the change point against it; local polynomial + harmonic fits that slide along a recording
  (:func:`local_fit`: the slow part and the rhythm's amplitude).
* :mod:`~rdmp_gym.signals.segmentation.rest`: the speed of the motion and where it rests (:func:`motion_speed`,
  :func:`rest_start`, :func:`rest_onset`).

A new kind of input (another sensor quantity, several sessions in one file) gets its own module beside these and
builds on the shared parts; the results are frozen dataclasses with times in seconds from the first sample.
Everything listed in ``__all__`` is importable from ``rdmp_gym.signals.segmentation``.
"""

from .demonstration import Segmentation, phase_shift, segment
from .ending import StopSegmentation, segment_ending
from .fourier import local_fit
from .period import PERIOD_METHODS, estimate_period, refine_period
from .recording import RhythmSegmentation, segment_rhythm
from .rest import motion_speed, rest_onset, rest_start

__all__ = [
    "PERIOD_METHODS",
    "RhythmSegmentation",
    "Segmentation",
    "StopSegmentation",
    "estimate_period",
    "local_fit",
    "motion_speed",
    "phase_shift",
    "refine_period",
    "rest_onset",
    "rest_start",
    "segment",
    "segment_ending",
    "segment_rhythm",
]
