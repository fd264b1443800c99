"""Fit a whole recording of a pose (position and orientation) and measure the fit.

:func:`fit_pose_recording` is :func:`~rdmp_gym.recordings.recording_fit.fit_recording` on the position and the
orientation's tangent coordinates side by side (:class:`~rdmp_gym.dmp.pose.PoseDemonstration`): the position alone sets
the timing (rhythm, rests, tempo), the tangent coordinates get their own slow part (the tool's slow turn during the
approach and the drift) and weights on the same canonical system. The dimensions of a DMP do not interact, so the
position part is the position-only fit's.

:func:`pose_report` measures the position as :func:`~rdmp_gym.recordings.recording_fit.recording_report` does and the
orientation in degrees: its cycle error against the recording's own cycle-to-cycle variation (in the tangent
coordinates, whose distances are rotation angles to first order about the reference), the angle between
reproduced and recorded orientations, and the peak angular acceleration against the smoothed recording's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..dmp import quaternion
from ..dmp.pose import Pose, PoseDemonstration, PoseDMP
from ..dmp.rhythmic import RhythmicDMP
from ..signals.demonstrations import Demonstration
from ..signals.filters import smooth_derivatives
from .recording_fit import ACCELERATION_SMOOTHING, RecordingFit, constant_columns, fit_recording, recording_report

__all__ = ["PoseFit", "fit_pose_recording", "pose_report", "smoothed_peak_angular_acceleration"]

_STEP = 1e-3        # s: the grid on which the reproduction's angular acceleration is measured


@dataclass(frozen=True, eq=False)
class PoseFit:
    """Result of :func:`fit_pose_recording`: the recording's fit (``recording.dmp`` over position and tangent
    coordinates, its segmentation and ``stop_at``) and the reference orientation ``[4]``."""

    recording: RecordingFit
    reference: np.ndarray

    @property
    def dmp(self) -> PoseDMP:
        """The fitted pose DMP."""
        return PoseDMP(self.recording.dmp, self.reference)

    def reproduce(self, t: np.ndarray) -> Pose:
        """The reproduced pose ``([T, p], [T, 4])`` at even times ``t [T]`` (from the start of the recording)."""
        return self.dmp.rollout(t, stop_at=self.recording.stop_at)


def fit_pose_recording(pose: PoseDemonstration, **keywords) -> PoseFit:
    """Fit one DMP to a whole pose recording; ``keywords`` as in
    :func:`~rdmp_gym.recordings.recording_fit.fit_recording` (hints ``period``, ``start``, ``end``, ``ending``; numbers
    of basis functions; ...)."""
    if not isinstance(pose, PoseDemonstration):
        raise TypeError(f"pose: expected a PoseDemonstration, got {type(pose).__name__}")
    if "timing_dims" in keywords:
        raise ValueError("timing_dims: the position sets the timing of a pose fit")
    return PoseFit(fit_recording(pose.demo, timing_dims=pose.n_position, **keywords), pose.reference)


def _part(result: RecordingFit, dmp: RhythmicDMP) -> RecordingFit:
    """``result`` with ``dmp`` (the DMP of some of its dimensions) in place of its DMP."""
    return RecordingFit(dmp=dmp, segmentation=result.segmentation, stop_at=result.stop_at)


def pose_report(pose: PoseDemonstration, result: PoseFit) -> dict[str, float | bool | None]:
    """How well ``result`` reproduces ``pose``: the keys of :func:`~rdmp_gym.recordings.recording_fit.recording_report`
    for the position, and for the orientation (degrees, deg/s^2):

    ``orientation_variation``, ``orientation_error``, ``orientation_error_ratio`` (the recording's cycle-to-cycle
    variation, the cycle error and their ratio, in the tangent coordinates), ``orientation_rmse`` (the angle
    between reproduced and recorded orientation over the rhythm), ``orientation_start_error``,
    ``orientation_rest_error`` (``None`` without a final rest), ``peak_angular_acceleration``,
    ``recording_peak_angular_acceleration`` (Savitzky-Golay smoothed over the same window as the position's),
    ``angular_acceleration_ratio`` and ``orientation_constant`` (whether the recorded orientation never changes, as
    a tool held level: the DMP holds it in its anchor; its variation is then 0 and its error the reproduction's
    turning about its mean over the rhythm, see :func:`~rdmp_gym.recordings.recording_fit.recording_report`).
    """
    fitted = result.recording
    report = recording_report(pose.position, _part(fitted, result.dmp.position))
    tangent = recording_report(pose.tangent, _part(fitted, result.dmp.tangent))
    seg, t = fitted.segmentation, pose.demo.t - pose.demo.t[0]
    reproduced = result.reproduce(pose.demo.t).orientation
    angles = np.degrees(quaternion.angle_between(reproduced, pose.orientations))
    rhythm = (t >= seg.rhythm_start) & (t <= seg.rhythm_end)
    peak = _peak_angular_acceleration(result, t[-1])
    recorded_peak = smoothed_peak_angular_acceleration(pose.tangent, pose.reference)
    report.update(orientation_variation=float(np.degrees(tangent["cycle_variation"])),
                  orientation_error=float(np.degrees(tangent["cycle_error"])),
                  orientation_error_ratio=tangent["error_ratio"],
                  orientation_rmse=float(np.sqrt(np.mean(angles[rhythm] ** 2))),
                  orientation_start_error=float(np.degrees(tangent["start_error"])),
                  orientation_rest_error=None if seg.rest_time is None else float(np.mean(angles[t >= seg.rest_time])),
                  peak_angular_acceleration=peak, recording_peak_angular_acceleration=recorded_peak,
                  angular_acceleration_ratio=peak / max(recorded_peak, 1e-12),
                  orientation_constant=len(constant_columns(pose.tangent.Y)) == pose.tangent.n_dims)
    return report


def _peak_angular_acceleration(result: PoseFit, duration: float) -> float:
    """The reproduction's peak angular acceleration (deg/s^2) on a ``_STEP`` grid over ``duration`` s."""
    orientation = result.reproduce(np.arange(0.0, duration, _STEP)).orientation
    return float(np.degrees(np.max(np.linalg.norm(quaternion.angular_acceleration(orientation, _STEP), axis=1))))


def smoothed_peak_angular_acceleration(tangent: Demonstration, reference: np.ndarray) -> float:
    """The peak angular acceleration (deg/s^2) of a recording's tangent coordinates ``[L, 3]`` about ``reference
    [4]``, smoothed as the position's in :func:`~rdmp_gym.recordings.recording_fit.recording_report`: at every sample,
    from the Savitzky-Golay tangent coordinates, rates and accelerations ``v, v', v''`` (the orientation along
    ``v + v' s + v'' s^2 / 2`` at ``s = -h, 0, h``, h = 1 ms)."""
    v, rate, acceleration = smooth_derivatives(tangent.Y, tangent.dt, ACCELERATION_SMOOTHING)
    path = np.stack([quaternion.from_tangent(v + rate * s + 0.5 * acceleration * s * s, reference)
                     for s in (-_STEP, 0.0, _STEP)])                                          # [3, L, 4]
    return float(np.degrees(np.max(np.linalg.norm(quaternion.angular_acceleration(path, _STEP), axis=-1))))
