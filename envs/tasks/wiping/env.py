"""``rdmp_gym/ArmarWipe-v3`` (and v1, v2, ``PandaWipe-v3``): episodic table wiping with a rhythmic DMP.

The wiping ids are made by the episodic face of every task (:class:`~rdmp_gym.envs.rhythmic_env.RhythmicTaskEnv`
with ``task="wipe"``), which reads the task from its description
(:class:`~rdmp_gym.envs.tasks.wiping.task.WipingTask`, ``env.task``: scene, context, DMP, action layout, plan, path
checks, the simulation hook, judgement, the dirt drawn on the frames). :class:`ArmarWipeEnv` is the same face made
from one :class:`~rdmp_gym.envs.tasks.wiping.settings.EnvConfig` (or its keywords), a name kept for existing code.
What each version changes (v2: the travelling pattern, solvable contexts, the smoothness measure, executable
success; v3: the composed scene of any robot and a smooth-path success) is listed in
:mod:`rdmp_gym.envs.tasks.wiping.versions`; ``version`` selects it (default 3, the current task).

One ``step`` is one whole DMP rollout (``terminated=True, truncated=False``):

1. the action ``a in [-1, 1]^n`` becomes DMP parameters ``theta = theta_imitation + scale * a`` (plus, for
   the last dimension, ``approach``, a fixed direction that lifts the approach:
   :mod:`rdmp_gym.envs.tasks.wiping.approach`);
2. the DMP, anchored at the dirt patch centre and started at the sponge start of the context, gives
   the sponge path ``P [T, 3]`` in the table frame (x, y on the table, z above it);
3. the path is checked (finite, inside the workspace, reachable by the IK with the sponge flat on the
   tilted table, joint speeds): an invalid one returns a graded penalty at once, ``info["valid"] = False``;
4. otherwise MuJoCo simulates it at the control rate with differential-IK joint targets and online
   wrist-force adaptation of the pressing depth along the actual table normal (the table height is
   unknown to the controller; its tilt is known from the context); a cup may stand in the approach;
5. the reward sums the terms of :mod:`rdmp_gym.envs.tasks.wiping.reward`, all in ``info["reward_terms"]``, and
   ``info["cost_trace"]`` gives the per-control-step cost for PI² (it sums to ``-reward``;
   ``info["cost_terms"]`` splits it by term);
   ``info["is_success"]``: coverage >= 0.95, force in band >= 90 % of the wiping phase, no collision
   (arm on the table, arm on the robot's body), the cup neither touched nor moved, a valid episode;
   ``info["failure_causes"]`` names the criteria an episode misses (:func:`failure_causes`, empty for a success).

Rendering: ``render_mode="rgb_array"`` renders offscreen with ``mujoco.Renderer``; on a headless
machine set ``MUJOCO_GL=egl`` (or ``osmesa``) before importing mujoco. Because an episode is a single
step, ``record_episode`` (or ``record_frames=True``) captures frames inside it.
"""

from __future__ import annotations

from typing import Any

from ...rhythmic_env import RhythmicTaskEnv
from .settings import EnvConfig
from .task import WipingTask, episode_success, failure_causes, outcome

__all__ = ["ArmarWipeEnv", "episode_success", "failure_causes", "outcome"]


class ArmarWipeEnv(RhythmicTaskEnv):
    """The wiping task on the episodic face, made from its settings; see the module docstring.

    ``gym.make("rdmp_gym/ArmarWipe-v3", **settings)`` and ``RhythmicTaskEnv("wipe", robot=..., version=...,
    **settings)`` make the same env; this name is kept for existing code.

    The settings come as one :class:`~rdmp_gym.envs.tasks.wiping.settings.EnvConfig` (``config``), as keywords
    (``gym.make``'s way), or both (the keywords change the config); every setting is validated for type and meaning,
    with an error that names it, and ``env.task.config`` saves to and loads from JSON.

    Args:
        config: all settings at once (default: ``EnvConfig()``).
        robot: the robot, a registered name (``"armar3"``, ``"panda"``) or a ``RobotDescription``
            (:mod:`rdmp_gym.envs.robots`).
        style: synthetic demonstration style 1..4 (1/2 circle, 3/4 figure-eight; 2/4 complex approach).
        demonstration: a user ``rdmp_gym.Demonstration`` ``Y [L, 3]`` in the table frame, in metres: x, y on
            the table, z above its surface (overrides ``style``; checked against the workspace before fitting).
        dmp: a saved DMP (a ``dmp.json`` path, e.g. a run's refined DMP, or a ``RhythmicDMP``) used as the
            imitation without fitting (overrides ``style``; excludes ``demonstration``).
        n_periodic, n_transient, fit_method: DMP fit settings (default the core's ``"trajectory"`` fit: the
            smoothest imitation, half the jerk of ``"ridge"``).
        groups: parameter groups in the action (default periodic weights, transient weights, initial condition,
            amplitude, and ``"approach"``: one dimension that raises or lowers the approach as a whole, see
            :mod:`rdmp_gym.envs.tasks.wiping.approach`; it needs ``"transient"``; v2 adds ``"sweep"``: the anchor
            travels over the patch, two action dimensions ``sweep_x``, ``sweep_y``, see
            :mod:`rdmp_gym.envs.tasks.wiping.coverage`).
        scales: per-group action scales (see :mod:`rdmp_gym.envs.action`; ``approach``: lift in m at +1).
        n_periods: periods of the pattern after the transient (default 4 in v1, 7 in v2); ``duration`` (s)
            overrides it.
        control_rate: control frequency (Hz); ``frame_skip`` (physics steps per control step) overrides it.
        timestep: physics step (s; default the model's 2 ms).
        target_force: normal force to hold while wiping (N) (controller and reward).
        force_band: (min, max) normal force (N) that wipes a cell; the max is also the excess-force limit.
        force_sigma: width (N) of the force-closeness reward.
        reward_weights: ``{term: weight}`` overrides (see :mod:`rdmp_gym.envs.tasks.wiping.reward`).
        adaptation: adapt the pressing depth from the wrist force (``False``: feed-forward preload only).
        admittance_gain: depth rate per newton of force error (m/(N s)).
        force_learning: also learn the pressing depth as a periodic function of the DMP's phase and feed it
            forward on the next periods (Gams et al. 2010; :mod:`rdmp_gym.envs.tasks.wiping.force_learning`); ``True``
            or a ``ForceProfileSettings``.
        context_ranges: ``{field: (low, high)}`` sampling ranges (see :mod:`rdmp_gym.envs.tasks.wiping.context`).
        obstacle: contexts may put a cup in the approach corridor (``False``: never).
        obstacle_probability: share of drawn contexts with a cup (where one fits).
        cell_size: dirt cell side (m).
        wear_rate: Preston coefficient of the dirt (1/(Pa m); see :mod:`rdmp_gym.envs.tasks.wiping.simulation`).
        penetration_limit: penetration (m) of a robot geom into the robot's body or (other than the
            sponge) into the table beyond which the episode is invalid (reason ``"penetration"``).
        limit_margin: distance to a joint limit (rad) that counts as "at the limit".
        ik_tolerance: (position m, angle rad) IK residuals beyond which a path is unreachable.
        max_joint_speed: joint speed (rad/s) of the planned path beyond which it is invalid (default: the robot's).
        xml_file: a hand-merged scene MJCF for the versions 1 and 2 (default: the robot's own scene;
            :class:`~rdmp_gym.envs.tasks.wiping.legacy.scene.WipeScene`).
        render_mode: ``None``, ``"rgb_array"`` (RGB frames), ``"depth_array"`` (depth in m) or ``"human"``
            (MuJoCo's viewer, following every control step; needs a display); width, height, camera: of the
            rendered frames.
        record_frames: capture frames during every step into :attr:`frames`; frame_stride: every how
            many control steps.
        version: the task version, 1, 2 or 3 (:mod:`rdmp_gym.envs.tasks.wiping.versions`; default 3, the current task as
            ``rdmp_gym/ArmarWipe-v3`` makes it); ``gym.make`` of an id sets its own.
        cup_clearance: execute every path with a clearance term that keeps the hand (fingers, thumb, palm,
            sponge) this many metres from the cup's side (:class:`~rdmp_gym.envs.tasks.wiping.clearance.CupClearance`,
            or one given); ``None`` (default): the path as commanded. The reward and the success criteria are the same;
            ``info["clearance_push"]`` gives the largest push of the path (m).
    """

    def __init__(self, config: EnvConfig | None = None, **settings: Any):
        config = EnvConfig.from_kwargs(**settings) if config is None else config.replace(**settings)
        task = WipingTask.build(config)
        render = config.render
        super().__init__(task, robot=task.robot, version=task.version, render_mode=render.render_mode,
                         width=render.width, height=render.height, camera=render.camera,
                         frame_stride=render.frame_stride, record_frames=render.record_frames)

