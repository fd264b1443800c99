"""The hand-over from the transient to the periodic pattern: the C2 test joins, the worst-window measure, the
off-path probe, the fade placement (its cause: what the mixture can express at all) and the targets."""

import numpy as np
import pytest

from rdmp_gym import RhythmicDMP
from rdmp_gym.dmp.fitting import (
    FADE_BEFORE_T,
    JOIN_FLOOR,
    START_PRIOR,
    fit_rhythmic,
    fit_trajectory,
    join_relief,
    relative_to_pattern,
    second_differences,
    trajectory_design,
)
from rdmp_gym.signals.demonstrations import Demonstration
from rdmp_gym.signals.segmentation import Segmentation
from rdmp_gym.synthetic.smoothness import (
    HANDOVER_TARGETS,
    draw_test_demonstrations,
    handover_figures,
    handover_misses,
    off_path_peak_ratio,
    off_path_starts,
    peak_acceleration,
    random_test_signal,
    worst_window_error,
)

DT = 1e-3
FORMER_DEFAULTS = {"n_transient": 40, "transient_lead": 1.0, "start_prior": 0.0, "join_width": 0.0}
"""A free start velocity, the full penalty at T and M = 40 from one spacing before the start."""


@pytest.fixture(scope="module")
def joins():
    """The 12 C2 joins of ``benchmarks/bench_fidelity.py`` (seed 0)."""
    return draw_test_demonstrations(np.random.default_rng(0), 12, join="quintic")


MODELS = {"default": {}, "smoothness 0.3": {"smoothness": 0.3}, "fade before T": FADE_BEFORE_T,
          "former defaults": FORMER_DEFAULTS}
"""The fit settings the hand-over figures compare."""


@pytest.fixture(scope="module")
def figures(joins):
    """Per model, the :func:`handover_figures` of each join (48 fits, ~18 CPU s: the tests that read all 12 joins
    are in the slow set; ``test_on_join_0_...`` checks one join in the default set)."""
    return {model: [handover_figures(signal, RhythmicDMP.fit(demo, **settings), demo.duration)
                    for signal, demo in joins]
            for model, settings in MODELS.items()}


def test_quintic_join_is_c2_at_T():
    """With join='quintic' the start meets the orbit at T with equal position, velocity and acceleration."""
    signal = random_test_signal(np.random.default_rng(3), join="quintic")
    T = signal.transient_length
    before = signal.derivatives(np.array([T - 1e-9]))
    after = signal.derivatives(np.array([T + 1e-9]))
    for order in range(3):
        assert np.allclose(before[order], after[order], atol=1e-5), order
    start = signal.derivatives(np.array([0.0]))
    assert np.allclose(start[1], 0.0) and np.allclose(start[2], 0.0)          # from rest


def test_worst_window_finds_a_local_fault():
    """A 0.1 s burst in an otherwise exact reproduction: the window covers it and its error is the burst's RMS
    over a 0.2 s window relative to the whole signal's RMS."""
    t = np.arange(0.0, 4.0, DT)
    truth = np.stack([np.sin(2 * np.pi * t), np.cos(2 * np.pi * t)], axis=1)
    Ydd = truth.copy()
    burst = (t >= 2.0) & (t < 2.1)
    Ydd[burst, 0] += 1.0
    error, at = worst_window_error(Ydd, truth, DT)
    assert 1.9 <= at <= 2.0 + 1e-9
    assert error == pytest.approx(np.sqrt(0.5), rel=0.02)          # RMS of truth is 1
    with pytest.raises(ValueError, match="Ydd"):
        worst_window_error(Ydd[:100], truth, DT)


def test_off_path_starts_leave_the_encoded_path(joins):
    demo = joins[0][1]
    dmp = RhythmicDMP.fit(demo)
    starts = off_path_starts(dmp)
    encoded = np.array([dmp.transients[0].phi0, dmp.transients[0].r0])
    assert starts.shape == (32, 2) and not np.any(np.all(np.isclose(starts, encoded), axis=1))
    ratio = off_path_peak_ratio(dmp, float(peak_acceleration(demo.Y, 1.0 / 100.0)), duration=2.0)
    assert np.isfinite(ratio) and ratio > 0.0


def test_fit_settings_are_checked(joins):
    demo = joins[0][1]
    with pytest.raises(ValueError, match="handover"):
        RhythmicDMP.fit(demo, handover="late")
    with pytest.raises(ValueError, match="prior"):
        RhythmicDMP.fit(demo, prior="linear")
    with pytest.raises(ValueError, match="transient_lead"):
        RhythmicDMP.fit(demo, transient_lead=-1.0)
    with pytest.raises(ValueError, match="smoothness"):
        RhythmicDMP.fit(demo, smoothness="gcv")
    with pytest.raises(ValueError, match="smoothness"):
        RhythmicDMP.fit(demo, smoothness=-0.1)
    for bad in ((0.3, 0.3, 0.3), (0.3, "gcv"), (0.3, -1.0)):
        with pytest.raises(ValueError, match="smoothness"):
            RhythmicDMP.fit(demo, smoothness=bad)
    with pytest.raises(ValueError, match="smoothness"):
        RhythmicDMP.fit(demo, method="ridge", smoothness=(0.3, 0.3))
    with pytest.raises(ValueError, match="start_prior"):
        RhythmicDMP.fit(demo, start_prior=-0.01)
    with pytest.raises(ValueError, match="join_width"):
        RhythmicDMP.fit(demo, join_width=float("nan"))


def _bump_fit_errors(noise: float, candidates: np.ndarray) -> tuple[float, list[float]]:
    """RMS error against the truth of a penalised fit of 30 Gaussian bumps to 200 samples of a smooth curve with
    ``noise``: with the penalty chosen among ``candidates`` by cross-validation, and with each candidate fixed."""
    rng = np.random.default_rng(1)
    t = np.linspace(0.0, 1.0, 200)
    centres = np.linspace(0.0, 1.0, 30)
    responses = np.exp(-0.5 * ((t[:, None] - centres) / 0.04) ** 2)
    truth = (np.sin(2 * np.pi * 3 * t) + 0.5 * np.cos(2 * np.pi * 5 * t))[:, None]
    samples = truth + noise * rng.standard_normal(truth.shape)
    differences = second_differences((30,), (False,), (1.0,), 1.0)

    def error(smoothness) -> float:
        weights, starts = fit_trajectory([responses], [np.ones((200, 1))], [samples], differences, smoothness, 1e-10)
        return float(np.sqrt(np.mean((responses @ weights + starts[0, 0] - truth) ** 2)))

    return error([candidates]), [error(float(value)) for value in candidates]


def test_cross_validation_chooses_the_penalty_the_noise_needs():
    """Among 1e-6..1e2, the cross-validated penalty is within 1.5x of the best fixed one on noisy samples and within
    2x on clean ones, where the strongest candidate is off by orders of magnitude (the bias that a fixed penalty
    leaves on clean or well-determined parts)."""
    candidates = np.logspace(-6.0, 2.0, 17)
    for noise in (0.0, 0.1):
        chosen, fixed = _bump_fit_errors(noise, candidates)
        assert chosen <= (1.5 if noise else 2.0) * min(fixed) + 1e-9, (noise, chosen, min(fixed))
    assert chosen < 0.5 * max(fixed)


def test_a_smoothness_pair_sets_each_family_and_auto_keeps_cross_validation(joins):
    demo = joins[3][1]
    fixed = RhythmicDMP.fit(demo, smoothness=0.3)
    assert np.allclose(RhythmicDMP.fit(demo, smoothness=(0.3, 0.3)).weights, fixed.weights)
    assert np.allclose(RhythmicDMP.fit(demo, smoothness=("auto", "auto")).weights, RhythmicDMP.fit(demo).weights)
    weak = RhythmicDMP.fit(demo, smoothness=("auto", 1e-3))
    strong = RhythmicDMP.fit(demo, smoothness=("auto", 10.0))
    roughness = [float(np.sum(np.diff(dmp.weights[:, dmp.basis.n_periodic:], 2, axis=1) ** 2))
                 for dmp in (weak, strong)]
    assert roughness[0] > 2.0 * roughness[1]


def test_pattern_prior_leaves_transient_weights_that_follow_the_pattern_unpenalised():
    """Rows of the pattern-relative penalty vanish on transient weights equal to their share of the pattern."""
    rng = np.random.default_rng(0)
    differences = np.zeros((3, 7))
    differences[:, 2:] = [[1, -2, 1, 0, 0], [0, 1, -2, 1, 0], [0, 0, 1, -2, 1]]       # on the 5 transient weights
    pattern, shares, periodic = rng.random((5, 2)), np.linspace(0.0, 1.0, 5), rng.normal(size=2)
    weights = np.concatenate([periodic, shares * (pattern @ periodic)])
    assert np.abs(relative_to_pattern(differences, 2, pattern, shares) @ weights).max() < 1e-12
    assert np.abs(differences @ weights).max() > 1e-3


def _best_transient_acceleration_error(signal, settings: dict) -> float:
    """The least acceleration error over the transient that any weights and start state give, on noise-free
    samples at 500 Hz with the true T: least squares on the rollout's acceleration (linear in both)."""
    clean = signal.demonstration(signal.transient_length + 5.0, rate=500.0, noise=0.0)
    parts = fit_rhythmic(clean, segmentations=[Segmentation(signal.period, signal.transient_length,
                                                            signal.anchor)], **settings)
    start = parts.transients[0]
    responses, columns, samples = trajectory_design(parts.canonical, parts.basis, [clean], [(start.phi0, start.r0)],
                                                    [start.length], parts.anchor, parts.alpha_z, 1)

    def second_derivative(values: np.ndarray) -> np.ndarray:
        return np.gradient(np.gradient(values, clean.dt, axis=0, edge_order=2), clean.dt, axis=0, edge_order=2)

    design = second_derivative(np.concatenate([responses[0], columns[0]], axis=1))
    target = second_derivative(samples[0])
    residual = design @ np.linalg.lstsq(design, target, rcond=None)[0] - target
    transient = clean.t < signal.transient_length
    acceleration = signal.derivatives(clean.t)[2]
    return float(np.sqrt(np.mean(np.sum(residual[transient] ** 2, axis=1))
                         / np.mean(np.sum(acceleration[transient] ** 2, axis=1))))


def test_the_fade_before_T_cannot_follow_a_c2_join(joins):
    """The cause of the ripple before T: while the transient family fades out the mixture is ``f_p + s (f_t - f_p)``
    with its share s falling to 1e-3, so a demonstration still off its cycle there (a C2 join to a 3-harmonic
    orbit) cannot be followed by any weights (measured 35 %); with the fade after T it can (2.8 %)."""
    signal = joins[3][0]
    assert _best_transient_acceleration_error(signal, FADE_BEFORE_T) > 0.25
    assert _best_transient_acceleration_error(signal, {}) < 0.04


def test_on_join_0_the_defaults_meet_every_target_where_the_fade_before_T_and_the_former_fit_do_not(joins):
    """The default-set check of the figures the slow tests read for all 12 joins, on join 0: the defaults and one
    fixed smoothness 0.3 meet every target, the fade before T and the former defaults do not; the defaults' transient
    acceleration error and worst window are under a third of the fade before T's (measured 9.0 % vs 29.7 % and
    16.5 % vs 49.8 %), the worst window within its bar where the former defaults' exceeds it (21.1 %), and the
    periodic acceleration error about as low as with the fixed smoothness (1.9 % vs 2.6 %)."""
    signal, demo = joins[0]
    rows = {model: handover_figures(signal, RhythmicDMP.fit(demo, **settings), demo.duration)
            for model, settings in MODELS.items()}
    assert set(HANDOVER_TARGETS) <= set(rows["default"])
    assert handover_misses(rows["default"]) == [] and handover_misses(rows["smoothness 0.3"]) == []
    assert handover_misses(rows["fade before T"]) and handover_misses(rows["former defaults"])
    for name in ("transient acceleration", "worst window"):
        assert rows["default"][name] < 0.35 * rows["fade before T"][name], name
    assert rows["default"]["worst window"] <= HANDOVER_TARGETS["worst window"] < rows["former defaults"]["worst window"]
    assert rows["default"]["periodic acceleration"] < 1.05 * rows["smoothness 0.3"]["periodic acceleration"]


@pytest.mark.slow
def test_defaults_cut_the_transient_error_of_the_fade_before_T_to_a_third(figures):
    """Over the 12 joins (measured medians 8.5 % vs 30.7 %, worst 22.2 % vs 85.3 %; worst windows: median 11.0 % vs
    32.1 %)."""
    new, old = (np.array([row["transient acceleration"] for row in figures[model]])
                for model in ("default", "fade before T"))
    assert np.median(new) < 0.35 * np.median(old) and new.max() < 0.35 * old.max()
    new, old = (np.array([row["worst window"] for row in figures[model]]) for model in ("default", "fade before T"))
    assert np.median(new) < 0.4 * np.median(old)


@pytest.mark.slow
def test_cross_validated_smoothness_loses_no_target_of_the_fixed_one(figures):
    """Per join, the defaults miss no target that one fixed smoothness 0.3 meets; the periodic acceleration error is
    about as low or lower on every join (measured at most 3.2 % against 4.5 %; join 5: 0.91 % against 0.90 %) and the
    median transient one lower too (8.5 % vs 10.7 %)."""
    for index, (new, old) in enumerate(zip(figures["default"], figures["smoothness 0.3"], strict=True)):
        assert set(handover_misses(new)) <= set(handover_misses(old)), index
        assert new["periodic acceleration"] < 1.05 * old["periodic acceleration"], index
    transient, periodic = ({model: np.array([row[name] for row in figures[model]])
                            for model in ("default", "smoothness 0.3")}
                           for name in ("transient acceleration", "periodic acceleration"))
    assert np.median(transient["default"]) < np.median(transient["smoothness 0.3"])
    assert periodic["default"].max() < 0.8 * periodic["smoothness 0.3"].max()


@pytest.mark.slow
def test_defaults_keep_the_periodic_position_and_off_path_targets_on_every_join(figures):
    keep = ("periodic acceleration", "transient position", "periodic position", "off-path peak")
    for index, row in enumerate(figures["default"]):
        assert not set(keep) & set(handover_misses(row)), (index, handover_misses(row))


@pytest.mark.slow
def test_defaults_meet_every_target_on_seven_joins(figures):
    """Every one of :data:`HANDOVER_TARGETS` on joins 0, 2, 5, 7, 9, 10 and 11 (the former defaults: on 2, 5, 7, 9, 10
    and 11; one fixed smoothness 0.3: on 0, 5, 7, 9, 10 and 11; the fade before T: on none)."""
    met = {model: [index for index, row in enumerate(rows) if not handover_misses(row)]
           for model, rows in figures.items()}
    assert met["default"] == [0, 2, 5, 7, 9, 10, 11]
    assert met["former defaults"] == [2, 5, 7, 9, 10, 11]
    assert met["smoothness 0.3"] == [0, 5, 7, 9, 10, 11]
    assert met["fade before T"] == []
    assert set(HANDOVER_TARGETS) <= set(figures["default"][0])


@pytest.mark.slow
def test_defaults_lose_no_target_of_the_former_fit_and_no_window_exceeds_the_bar(figures):
    """Per join, the defaults miss no target that the former defaults (a free start velocity, the full penalty at T,
    M = 40 from one spacing before the start) meet; every worst 0.2 s window is within the 20 % bar (measured at most
    17.7 %, was up to 38.9 %: joins 0, 1, 3 and 8 missed it) and the largest jerk ratio halves (5.5x, was 10.2x)."""
    for index, (new, old) in enumerate(zip(figures["default"], figures["former defaults"], strict=True)):
        assert set(handover_misses(new)) <= set(handover_misses(old)), index
    windows = {model: [row["worst window"] for row in figures[model]] for model in ("default", "former defaults")}
    assert max(windows["default"]) <= HANDOVER_TARGETS["worst window"] < max(windows["former defaults"])
    jerks = {model: max(row["jerk"] for row in figures[model]) for model in ("default", "former defaults")}
    assert jerks["default"] < 0.6 * jerks["former defaults"]


def test_the_fit_keeps_a_start_from_rest_at_rest(joins):
    """Noise-free C2 joins that start at rest (joins 1, 3 and 6, the worst): with a free start velocity the fit trades
    it against the first weights (measured 49-82 mm/s, and a spike of acceleration after the start); by default
    cross-validation pulls it to rest (measured at most 1.3 mm/s)."""
    for index in (1, 3, 6):
        demo = joins[index][1]
        clean = Demonstration(demo.t, demo.truth.clean, truth=demo.truth)
        free = fit_rhythmic(clean, start_prior=0.0).transients[0].start_velocity
        pulled = fit_rhythmic(clean).transients[0].start_velocity
        assert np.abs(free).max() > 0.04 and np.abs(pulled).max() < 0.003, (index, free, pulled)


def test_the_fit_keeps_a_moving_start_moving(joins):
    """The same joins from 0.4 s on, where they move at 0.14-0.19 m/s: cross-validation leaves the start velocity free
    (the default's equals the free fit's: errors 16-42 mm/s), where the pull would hold it near rest."""
    for index in (1, 3, 6):
        signal, demo = joins[index]
        keep = demo.t >= 0.4 - 1e-9
        moving = Demonstration(demo.t[keep] - demo.t[keep][0], demo.Y[keep])
        truth = signal.derivatives(demo.t[keep][:1])[1][0]
        auto, free, pulled = (fit_rhythmic(moving, **settings).transients[0].start_velocity
                              for settings in ({}, {"start_prior": 0.0}, {"start_prior": START_PRIOR}))
        np.testing.assert_allclose(auto, free, atol=1e-9)
        assert np.abs(auto - truth).max() < 0.05 < np.abs(pulled - truth).max(), (index, auto, pulled, truth)


def test_join_relief_dips_to_the_floor_at_T():
    times = np.linspace(0.0, 2.0, 41)
    relief = join_relief(times, 1.0, 0.1)
    assert relief[20] == pytest.approx(JOIN_FLOOR) and relief.min() == relief[20]
    assert np.all(relief[np.abs(times - 1.0) > 0.5] > 0.999)
    assert np.array_equal(join_relief(times, 1.0, 0.0), np.ones(41))
