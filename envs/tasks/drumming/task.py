"""The drumming task: strike a drum on the beat of a metronome whose tempo changes once, then stop at rest.

The DMP (fitted to :func:`~.demonstration.drumming_demonstration` with a stop) starts at rest beside the drum; its
transient brings the stick above the membrane, and its phase and frequency follow the metronome's beat signal
online through the adaptive-frequency oscillator (:class:`rdmp_gym.dmp.frequency.AdaptiveFrequencyStepper`, started at
the announced tempo): when the tempo changes, the DMP adapts without a re-plan. After the last beat the DMP is asked
to stop and its stop transient brings the stick to rest.

Action (after the DMP's groups ``periodic``, ``transient``, ``amplitude``, ``stop``): ``coupling`` (the
oscillator's gain ``K = 2 * 4**(1.5 a)``, 1/s), ``phase_gain`` (``k_phi = 2 * 4**(1.5 a)``, 1/s) and ``phase`` (the beat
signal's shift, ``0.6 a`` rad: strike earlier or later than the beat).

Beats: those after the transient up to 2.6 s before the end; the first two are a warm-up, and the first beat at the
new tempo cannot be anticipated by a follower: the other beats are the **counted** ones.

Success: at least 90 % of the counted beats struck (one strike in the beat's window, within ``tolerance`` of the
beat, its impulse in ``impulse_band``), no extra strike (a double bounce, a strike outside the beats' windows),
nothing touched but the membrane by the tip (no rim, no other part of the drum or the table, not the robot's own
body), a smooth executable path (planned peak joint acceleration within the robot's limit, jerk at most
``max_jerk_ratio`` times the imitation's) and the stick at rest at the end (tip speed below ``rest_speed``).
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import cached_property
from typing import Any

import mujoco
import numpy as np

from rdmp_gym import RhythmicDMP
from rdmp_gym.dmp.frequency import CanonicalSchedule, Retunes
from rdmp_gym.dmp.stopping import fit_ending
from rdmp_gym.validation import SettingTypeError, check_number, check_pair

from ...contract import Metric
from ...robots import RobotDescription
from ...task_scene import rotation_from_tilt
from ..description import Outcome, TaskDescription, TaskPlan, ToolPath
from .context import FIELDS, DrumContext, DrumContextSpec
from .demonstration import drumming_demonstration
from .metronome import Metronome
from .scene import add_drum, add_stick, place_drum
from .strikes import Strikes, score_beats

__all__ = ["DrumTask"]

#: the last beat comes this long (s) before the end of the episode: time for the stop and the rest
_STOP_RESERVE = 3.0
#: the end over which the stick must be at rest (s)
_REST_WINDOW = 0.3
#: what a missed success criterion costs once, beside its graded cost
_MISS = 0.5


class DrumTask(TaskDescription):
    """The drumming task; see the module docstring.

    Args:
        context: the context's ranges (:class:`~.context.DrumContextSpec`; its ``change_window`` within the episode).
        tolerance: a strike's timing tolerance (s, > 0).
        impulse_band: (min, max) impulse of a strike (N s, 0 <= min < max): softer makes no sound, harder damages.
        max_jerk_ratio: the largest integrated squared jerk of the path, relative to the imitation's in the context
            (>= 1: the imitation's own ratio is 1).
        rest_speed: the tip's largest speed (m/s, > 0) over the last 0.3 s for the stick to be at rest.

    A setting out of its range is a ValueError naming it (a TypeError for one that is not a number).
    """

    name = "Drum"
    versions = (1,)
    groups = ("periodic", "transient", "amplitude", "stop")
    #: the weights' scales make a uniformly random action a rough path (its jerk a median 4.9x the imitation's on 24
    #: contexts, none a success); at 0.1 half of them stayed within the 2x of success and 2-3 of 24 succeeded
    scales: Mapping[str, float] = {"periodic": 0.2, "transient": 0.2, "amplitude": 0.5, "stop": 0.2}
    extras: Mapping[str, float] = {"coupling": 1.5, "phase_gain": 1.5, "phase": 0.6}
    duration = 10.0
    control_rate = 100.0
    #: per episode: the share of the counted beats struck, and the mean |strike - beat| over them
    metrics = (Metric("struck_fraction", "struck fraction"),
               Metric("mean_abs_timing_error", "timing error (s)", higher_is_better=False, unit="s"))

    def __init__(self, context: DrumContextSpec | None = None, tolerance: float = 0.05,
                 impulse_band: tuple[float, float] = (0.1, 1.0), max_jerk_ratio: float = 2.0,
                 rest_speed: float = 0.02):
        if context is not None and not isinstance(context, DrumContextSpec):
            raise SettingTypeError(f"context: expected a DrumContextSpec, got {type(context).__name__}")
        self.context_spec = DrumContextSpec() if context is None else context
        self.tolerance = check_number(tolerance, "tolerance", low=0.0, what=" (s)")
        low, high = check_pair(impulse_band, "impulse_band", "the (min, max) impulse in N s")
        if not 0 <= low < high:
            raise ValueError(f"impulse_band: expected (min, max) with 0 <= min < max (N s), got {impulse_band!r}")
        self.impulse_band = (low, high)
        # the jerk is measured relative to the imitation's in the same context (ratio 1): a bound below 1 would fail
        # the imitation itself, the action 0 every learner starts from
        self.max_jerk_ratio = check_number(max_jerk_ratio, "max_jerk_ratio", low=1.0, strict_low=False,
                                           what=" (the path's integrated squared jerk over the imitation's)")
        self.rest_speed = check_number(rest_speed, "rest_speed", low=0.0, what=" (m/s)")
        self._last_schedule: CanonicalSchedule | None = None
        spec, last_beat = self.context_spec, self.duration - _STOP_RESERVE
        latest = spec.latest_change(last_beat, spec.tempo[0])
        if spec.change_window[1] > latest:
            raise ValueError(f"context: change_window {spec.change_window} ends after {latest:g} s, the latest time "
                             f"whose beat at the slowest tempo ({spec.tempo[0]:g} bpm) comes by the episode's last "
                             f"beat ({last_beat:g} s): the tempo would not change within the episode")

    @classmethod
    def build(cls, version: int | None = None, **settings: Any) -> DrumTask:
        """The description of ``version`` (None: the latest) with ``settings``: this task for version 1,
        :class:`~.retuning.RetuningDrumTask` for version 2."""
        from .retuning import RetuningDrumTask

        descriptions = {1: DrumTask, 2: RetuningDrumTask}
        if version is not None and version not in descriptions:
            raise ValueError(f"version: the drumming task has the versions {sorted(descriptions)}, got {version!r}")
        return descriptions[max(descriptions) if version is None else version](**settings)

    @classmethod
    def face_settings(cls, robot: Any, version: int) -> dict[str, Any]:
        """The version is the task's setting (the second adds a value and a state of its own)."""
        return {"version": version}

    # ------------------------------------------------------------------ objects and context
    def compose(self, spec: mujoco.MjSpec, robot: RobotDescription, robot_prefix: str, tool_prefix: str) -> None:
        add_stick(spec, robot, robot_prefix, tool_prefix)
        add_drum(spec, robot, robot_prefix, tool_prefix)

    def context_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return self.context_spec.low, self.context_spec.high

    def context_fields(self) -> Mapping[str, tuple[int, int]]:
        """The observation's fields (:data:`~.context.FIELDS`: the drum's position, height and tilt, the tempo)."""
        return FIELDS

    def sample_context(self, rng: np.random.Generator, options: Mapping[str, Any] | None) -> DrumContext:
        return self.context_spec.sample(rng, options, last_beat=self.duration - _STOP_RESERVE)

    def frame(self, context: DrumContext, table_origin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The drum frame in the world: the membrane's centre ``[3]`` and the drum's axes ``[3, 3]``."""
        origin = table_origin + np.r_[context.drum_position, context.drum_height]
        return origin, rotation_from_tilt(*context.drum_tilt)

    def place(self, model: mujoco.MjModel, context: DrumContext) -> None:
        table = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "table")
        centre, _ = self.frame(context, model.body_pos[table])
        place_drum(model, centre, context.drum_tilt, context.drum_height)

    def cue(self, context: DrumContext, times: np.ndarray) -> np.ndarray:
        """The metronome's beat signal ``[T]`` (what a step-based policy hears)."""
        return self.metronome(context).signal(times)

    def workspace(self, robot: RobotDescription) -> tuple[np.ndarray, np.ndarray]:
        low, high = robot.workspace
        return low, np.r_[high[:2], high[2] + 0.15]       # the stick reaches above the sponge's box

    # ------------------------------------------------------------------ the DMP and its plan
    def imitation(self) -> RhythmicDMP:
        return self._imitation

    @cached_property
    def _imitation(self) -> RhythmicDMP:
        return fit_ending(drumming_demonstration(), n_periodic=20, n_transient=20)

    @cached_property
    def strike_phase(self) -> float:
        """The imitation's phase (rad, mod 2 pi) where the tip first reaches the membrane's plane on its way down."""
        dmp = self._imitation
        start = dmp.transients[0]
        t = np.arange(0.0, start.length + 3.0 * dmp.period, 1e-3)
        z = dmp.rollout(t)[:, 2]
        after = t >= start.length
        crossing = np.flatnonzero(after[1:] & (z[:-1] > 0.0) & (z[1:] <= 0.0))[0] + 1
        return float(np.mod(start.phi0 + dmp.canonical.omega * t[crossing], 2.0 * np.pi))

    def stop_request(self, metronome: Metronome, last_beat: float) -> float:
        """When (s) to ask for the stop so that the last stroke lands on ``last_beat`` (s): the stop leaves the cycle
        at the demonstrated exit phase, and one more stroke follows the exit; the request comes half a radian of
        phase before the exit that precedes the last beat by that stroke."""
        lead = np.mod(self.strike_phase - self._imitation.ending.exit_phase, 2.0 * np.pi) + 2.0 * np.pi - 0.5
        tempo = metronome.new_tempo if last_beat > metronome.change_time else metronome.tempo
        return float(last_beat - lead / (2.0 * np.pi * tempo / 60.0))

    def metronome(self, context: DrumContext) -> Metronome:
        """The metronome of ``context``."""
        start = self._imitation.transients[0].phi0
        return Metronome.changing_at_beat(context.tempo, context.new_tempo, context.change_time, start,
                                          self.strike_phase)

    def beats(self, metronome: Metronome) -> tuple[np.ndarray, np.ndarray]:
        """The beats ``[B]`` (s) up to the reserve for the stop, and which are counted ``[B]``: not the count-in
        (beats during the transient), not the first two after it, not the first at the new tempo."""
        transient = self._imitation.transients[0].length * self._imitation.canonical.omega / metronome.omega
        beats = metronome.beats(self.duration - _STOP_RESERVE)
        playing = beats > transient
        counted = playing & (np.cumsum(playing) > 2)
        first_new = np.flatnonzero(beats > metronome.change_time + 1e-9)
        if first_new.size:
            counted[first_new[0]] = False
        return beats, counted

    def plan(self, dmp: RhythmicDMP, theta: np.ndarray, extras: np.ndarray, context: DrumContext,
             times: np.ndarray, table_origin: np.ndarray) -> TaskPlan:
        params = dmp.with_params(theta, self.groups)
        metronome = self.metronome(context)
        beats, counted = self.beats(metronome)
        dt = float(times[1] - times[0])
        settings, signal = self._rhythm(extras, metronome, times)
        stop_at = self.stop_request(metronome, beats[-1]) if beats.size else times[-1]
        stopping = np.flatnonzero(times >= stop_at)
        schedule = self._schedule(params, signal, dt, int(stopping[0]) if stopping.size else None, settings,
                                  self._retunes(extras, metronome, times))
        path = schedule.rollout(params)[:-1]
        origin, rotation = self.frame(context, table_origin)
        return TaskPlan(path, origin, rotation, {"beats": beats, "counted": counted, "stop_at": stop_at,
                                                 "change_time": metronome.change_time, "schedule": schedule})

    def resume_plan(self, live: TaskPlan, step: int, dmp: RhythmicDMP, theta: np.ndarray, extras: np.ndarray,
                    context: DrumContext, times: np.ndarray, table_origin: np.ndarray) -> TaskPlan:
        """The plan of ``theta`` and ``extras`` from control step ``step`` on: the rhythm follower goes on from its
        state in the running plan ``live`` there with the new gains and beat shift (a change of them retunes the
        follower; replaying it from the start would jump its phase), the transformation system follows the resumed
        canonical time. The same gains and shift resume the running schedule itself."""
        return self._resumed(live, step, dmp, theta, extras, context, times)

    def _resumed(self, live: TaskPlan, step: int, dmp: RhythmicDMP, theta: np.ndarray, extras: np.ndarray,
                 context: DrumContext, times: np.ndarray, retune: float | None = None) -> TaskPlan:
        """:meth:`resume_plan`, the follower's frequency set to ``retune`` (rad/s) at ``step`` where given
        (:meth:`~rdmp_gym.dmp.frequency.CanonicalSchedule.resume`)."""
        params = dmp.with_params(theta, self.groups)
        running = live.extras["schedule"]
        metronome = self.metronome(context)
        settings, signal = self._rhythm(extras, metronome, times)
        settings["frequency"] = running.settings["frequency"]         # the follower's start stays the plan's
        retunes = self._retunes(extras, metronome, times)
        same = (retune is None and settings == running.settings and retunes == running.retunes
                and np.array_equal(signal[step:], running.u[step:, 0]))
        schedule = running if same else running.resume(params, step, signal, retune=retune, retunes=retunes,
                                                        **settings)
        return TaskPlan(schedule.rollout(params)[:-1], live.origin, live.rotation, {**live.extras,
                                                                                    "schedule": schedule})

    @staticmethod
    def _rhythm(extras: np.ndarray, metronome: Metronome, times: np.ndarray) -> tuple[dict[str, float], np.ndarray]:
        """The follower's settings of the task's values ``extras`` (coupling, phase gain, shift) and the beat
        signal ``[T]`` it follows at the control times ``times [T]``."""
        coupling, phase_gain, shift = extras
        settings = {"coupling": 2.0 * 4.0**coupling, "phase_gain": 2.0 * 4.0**phase_gain, "frequency": metronome.omega}
        return settings, metronome.signal(times, shift=shift)

    @staticmethod
    def _retunes(extras: np.ndarray, metronome: Metronome, times: np.ndarray) -> Retunes | None:
        """The follower's scheduled frequency corrections of the task's values (none in this version)."""
        return None

    def _schedule(self, dmp: RhythmicDMP, signal: np.ndarray, dt: float, stop_step: int | None,
                  settings: Mapping[str, float], retunes: Retunes | None = None) -> CanonicalSchedule:
        """The canonical schedule of the plan's stepper (:class:`~rdmp_gym.dmp.frequency.CanonicalSchedule`) over
        the beat signal ``signal [T]``, its stop requested before step ``stop_step``, its frequency corrected by
        ``retunes``: the last one recorded where it matches (a plan of other weights, amplitude or stop weights in
        the same context with the same extras), else a new recording."""
        schedule = self._last_schedule
        if schedule is None or not schedule.matches(dmp, signal, dt, stop_step, retunes, **settings):
            schedule = self._last_schedule = CanonicalSchedule.record(dmp, signal, dt, stop_step, retunes,
                                                                      **settings)
        return schedule

    # ------------------------------------------------------------------ the cycle-level face
    def cycle_state_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The default's (the tip's position and its offset from its path), then the timing errors of the last two
        beats played (s, within ±:data:`_ERROR_BOUND`) and whether the last was missed (0 or 1)."""
        low, high = super().cycle_state_bounds()
        return np.r_[low, -_ERROR_BOUND, -_ERROR_BOUND, 0.0], np.r_[high, _ERROR_BOUND, _ERROR_BOUND, 1.0]

    def cycle_state(self, face: Any, step: int | None, overlay: Any) -> np.ndarray:
        """The default's, then the last two played beats' timing errors and the last one's miss, from the membrane's
        force up to control step ``step`` (``overlay``: the simulation core and its record so far); a beat is played
        once the window that could hold its strike has passed, and a missed beat's error is the bound."""
        errors, missed = np.zeros(2), 0.0
        if step is not None and overlay is not None:
            plan = face.solution.plan
            errors, missed = self._played_errors(overlay.sensors[: step * face.frame_skip], plan, face,
                                                 step * face.dt)
        return np.r_[super().cycle_state(face, step, overlay), errors, missed]

    def _played_errors(self, sensors: np.ndarray, plan: TaskPlan, face: Any, now: float
                       ) -> tuple[np.ndarray, float]:
        """``(errors [2], missed)`` of the last two beats played by ``now`` (s) (see :meth:`cycle_state`)."""
        beats = np.asarray(plan.extras["beats"])
        gaps = np.diff(beats) if beats.size > 1 else np.full(1, np.inf)
        played = beats[beats + 0.5 * np.r_[gaps, gaps[-1:]][: beats.size] <= now]
        if played.size < 2:
            return np.zeros(2), 0.0
        hit = sensors[:, face.scene.sensor["drum_hit"]]
        strikes = Strikes.from_force(np.abs(hit[:, 1:4] @ plan.rotation[:, 2]), face.dt / face.frame_skip)
        error = score_beats(strikes, played, self.tolerance, self.impulse_band).error[-2:]
        missed = float(np.isnan(error[-1]))
        return np.clip(np.nan_to_num(error, nan=_ERROR_BOUND), -_ERROR_BOUND, _ERROR_BOUND), missed

    # ------------------------------------------------------------------ judgement
    def evaluate(self, path: ToolPath, context: DrumContext, sensor: Mapping[str, slice]) -> Outcome:
        plan, steps, frame_skip = path.plan, path.steps, path.frame_skip
        count = len(plan.path)
        fine_dt = path.dt / frame_skip
        live = path.sensors[: steps * frame_skip]
        hit = live[:, sensor["drum_hit"]]
        force = np.abs(hit[:, 1:4] @ plan.rotation[:, 2])
        strikes = Strikes.from_force(force, fine_dt)
        beats, counted = plan.extras["beats"], plan.extras["counted"]
        score = score_beats(strikes, beats, self.tolerance, self.impulse_band) if beats.size >= 2 else None
        touches = _touches(live, sensor, hit[:, 0])
        bad_steps = np.zeros(count)
        for column in touches.values():
            bad_steps[: steps] += column.reshape(steps, frame_skip).any(axis=1)
        speed = np.linalg.norm(np.diff(path.tip[:steps], axis=0), axis=1) / path.dt
        window = max(1, round(_REST_WINDOW / path.dt))
        end_speed = float(speed[-window:].max()) if steps == count and speed.size else np.inf
        cost, terms = self._costs(score, strikes, counted, beats, bad_steps, end_speed, path, count)
        n_counted = max(int(counted.sum()), 1)
        struck = float(score.struck[counted].sum()) / n_counted if score is not None else 0.0
        doubles = int(np.sum(score.count[counted] > 1)) if score is not None else 0
        extra = score.extra if score is not None else len(strikes.onsets)
        info = {"struck_fraction": struck, "n_beats": int(counted.sum()), "double_strikes": doubles,
                "extra_strikes": int(extra), "end_speed": end_speed, "jerk_ratio": path.jerk_ratio,
                "peak_joint_accel": path.peak_joint_accel, "tempo": context.tempo, "new_tempo": context.new_tempo,
                "change_time": plan.extras["change_time"], "beat_times": beats, "counted_beats": counted,
                "strike_times": strikes.onsets, "strike_impulses": strikes.impulses,
                "timing_error": score.error if score is not None else np.full(len(beats), np.nan),
                "force_trace": force, **{f"{name}_steps": int(column.any(axis=0).sum() if column.ndim > 1
                                                              else column.sum()) for name, column in touches.items()}}
        info["mean_abs_timing_error"] = float(np.nanmean(np.abs(info["timing_error"][counted]))) if (
            score is not None and np.isfinite(info["timing_error"][counted]).any()) else np.nan
        causes = self._causes(info, path)
        return Outcome(terms, cost, info, causes)

    def _costs(self, score: Any, strikes: Strikes, counted: np.ndarray, beats: np.ndarray, bad_steps: np.ndarray,
               end_speed: float, path: ToolPath, count: int) -> tuple[np.ndarray, dict[str, float]]:
        """The per-step cost ``[T]`` and the reward terms, each charged where it happens. Every success criterion an
        episode misses also costs a fixed :data:`_MISS` once, so that a return that beats another is a success where
        one is possible."""
        n_counted = max(int(counted.sum()), 1)
        step_of = np.minimum((np.asarray(beats) / path.dt).astype(int), count - 1)
        traces = {name: np.zeros(count) for name in ("timing", "impulse", "extra", "contact", "smooth", "rest")}
        if score is None:
            traces["timing"][-1] = 4.0 + _MISS
        else:
            error = np.nan_to_num(np.abs(score.error) / self.tolerance, nan=2.0)
            np.add.at(traces["timing"], step_of[counted], np.minimum(error**2, 4.0)[counted] / n_counted)
            if score.struck[counted].sum() < 0.9 * n_counted:
                traces["timing"][-1] += _MISS
            np.add.at(traces["extra"], step_of, _MISS * np.maximum(score.count - 1, 0) * counted)
            np.add.at(traces["extra"], np.minimum(strikes.first // path.frame_skip, count - 1)[score.strike_beat < 0],
                      _MISS)
        strike_steps = np.minimum(strikes.first // path.frame_skip, count - 1)
        low, high = self.impulse_band
        octaves = np.abs(np.log2(np.clip(strikes.impulses, 1e-6, None) / np.clip(strikes.impulses, low, high)))
        np.add.at(traces["impulse"], strike_steps, (np.minimum(octaves**2, 4.0) + _MISS * (octaves > 0)) / n_counted)
        traces["contact"] = 0.05 * bad_steps
        if bad_steps.any():
            traces["contact"][int(np.argmax(bad_steps > 0))] += _MISS
        rough = max(0.0, path.jerk_ratio - 1.0)
        fast = max(0.0, path.peak_joint_accel / path.max_joint_accel - 1.0)
        traces["smooth"][:] = (min(rough, 5.0) + min(fast, 5.0)) / count
        traces["smooth"][-1] += _MISS * ((path.jerk_ratio > self.max_jerk_ratio) + (fast > 0))
        traces["rest"][-1] = min(end_speed / self.rest_speed, 10.0) * 0.1 + _MISS * (end_speed > self.rest_speed)
        cost = sum(traces.values())
        return cost, {name: -float(trace.sum()) for name, trace in traces.items()}

    def _causes(self, info: dict, path: ToolPath) -> tuple[str, ...]:
        met = {"timing": info["struck_fraction"] >= 0.9,
               "extra strike": info["double_strikes"] == 0 and info["extra_strikes"] == 0,
               "rim": info["rim_steps"] == 0,
               "drum contact": info["drum_steps"] == 0,
               "arm collision": info["table_steps"] == 0,
               "self-collision": info["self_steps"] == 0,
               "joint acceleration": path.peak_joint_accel <= path.max_joint_accel,
               "jerk": path.jerk_ratio <= self.max_jerk_ratio,
               "rest": info["end_speed"] <= self.rest_speed}
        return tuple(name for name, ok in met.items() if not ok)


#: the bound (s) of the timing errors the cycle-level face observes (a missed beat observes it)
_ERROR_BOUND = 0.15


def _touches(live: np.ndarray, sensor: Mapping[str, slice], tip_found: np.ndarray) -> dict[str, np.ndarray]:
    """Per physics step: the rim touched, any other part of the drum touched by anything but the tip on the membrane,
    a robot geom on the table, the arm on the robot's own body (``{name: [N] bool}``)."""
    own = [name for name in sensor if name.startswith("arm_")]
    self_touch = (np.any(np.stack([live[:, sensor[name]][:, 0] > 0 for name in own]), axis=0) if own
                  else np.zeros(len(live), dtype=bool))
    return {"rim": live[:, sensor["robot_rim"]][:, 0] > 0,
            "drum": live[:, sensor["robot_drum"]][:, 0] - tip_found > 0.5,
            "table": live[:, sensor["robot_table"]][:, 0] > 0,
            "self": self_touch}
