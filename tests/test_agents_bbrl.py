"""``bbrl``, the neural contextual learner: the trust region holds, the covariance stays positive definite,
resume is exact, bad options are clear errors, and it learns a contextual problem that the random-return
control does not (MuJoCo-free toys; the wiping task is in the benchmarks)."""

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np
import pytest
import torch
from rdmp_gym.agents.learners import BBRLConfig, EpisodeBatch, SearchSpace, make_learner, policy_from_state
from rdmp_gym.agents.learners.bbrl import gaussian_kl, sample_weights
from rdmp_gym.agents.learners.smooth_exploration import squash, unsquash

torch.set_num_threads(1)
N = 12
GAINS = np.random.default_rng(5).uniform(-0.5, 0.5, (N, 2))


def _space():
    return SearchSpace({"periodic": slice(0, N - 2), "amplitude": slice(N - 2, N)}, 2, np.zeros(2), np.ones(2))


def _target(contexts):
    return 0.2 + contexts @ GAINS.T


def _batch(actions, returns, traces=None, seeds=None):
    """An ``EpisodeBatch`` of ``k`` episodes: no cost trace and reset seed 0 unless given (``[k, T]``, ``[k]``)."""
    k = len(returns)
    traces = np.zeros((k, 1)) if traces is None else traces
    seeds = np.zeros(k) if seeds is None else seeds
    return EpisodeBatch(actions, np.asarray(returns, dtype=float), traces, np.ones(k, dtype=bool),
                        np.asarray(seeds, dtype=np.int64))


def _run(learner, updates, seed=0, random_returns=False):
    """Learn ``max -|a - target(s)|²`` over ``s ~ U[-1, 1]²``; the held-out loss before and after, and the KLs."""
    rng = np.random.default_rng(100 + seed)
    held_out = rng.uniform(-1, 1, (50, 2))

    def loss():
        return np.mean(np.sum((learner.policy_actions(held_out) - _target(held_out)) ** 2, axis=1))

    before, kls = loss(), []
    for _ in range(updates):
        contexts = rng.uniform(-1, 1, (10, 2))
        actions = learner.ask(contexts)
        returns = -np.sum((actions - _target(contexts)) ** 2, axis=1)
        learner.tell(_batch(actions, rng.standard_normal(10) if random_returns else returns))
        kls.append(learner.last_kl)
    return before, loss(), np.array(kls)


def _learner(seed=0, **options):
    return make_learner("bbrl", np.zeros(N), 10, np.random.default_rng(seed), options, space=_space())


def test_learns_a_contextual_quadratic_and_the_random_return_control_does_not():
    """The toy's optimum is not smooth in the weights, so the exploration is independent here (length 0)."""
    before, after, _ = _run(_learner(length=0.0, epsilon=0.2), 40)
    control_before, control_after, _ = _run(_learner(length=0.0, epsilon=0.2), 40, random_returns=True)
    assert after < 0.4 * before
    assert control_after > 0.8 * control_before


@pytest.mark.parametrize("epsilon", [0.01, 0.2])
def test_every_update_stays_within_the_trust_region(epsilon):
    """With a learning rate far too large for the bound, each update is shrunk to it, and still moves."""
    _, _, kls = _run(_learner(epsilon=epsilon, learning_rate=0.1), 8)
    assert np.all(kls <= epsilon + 1e-9)
    assert np.mean(kls > 0.2 * epsilon) > 0.5


def test_the_covariance_stays_positive_definite_and_smooth():
    learner = _learner(rank=3)
    _run(learner, 10)
    with torch.no_grad():
        covariance = learner.policy.covariance(learner.config.min_sigma).numpy()
    assert np.linalg.eigvalsh(covariance).min() > 0
    samples = learner.rng.standard_normal((2000, N)) @ np.linalg.cholesky(covariance).T
    weights = samples[:, :5]                                    # one DoF's periodic weights: neighbours correlate
    assert np.corrcoef(weights[:, 0], weights[:, 1])[0, 1] > 0.5


def test_the_low_rank_factor_learns_from_its_small_random_start():
    """At ``U = 0`` the gradient of ``U U^T`` vanishes, so the factor starts small but not at zero, and moves."""
    learner = _learner(rank=2)
    start = learner.policy.low_rank.detach().clone()
    assert 0 < torch.linalg.norm(start) < 0.05 * learner.config.sigma * np.sqrt(N * 2)
    _run(learner, 5)
    assert torch.linalg.norm(learner.policy.low_rank.detach() - start) > torch.linalg.norm(start)
    assert _learner().policy.low_rank.shape == (N, 0)           # the default: no factor


@pytest.mark.parametrize("options", [{}, {"baseline": "network", "history": 2}, {"linear": True},
                                     {"linear": True, "linear_fit": "ridge"}])
def test_resume_is_exact_and_the_state_gives_the_policy(options):
    learner = _learner(**options)
    _run(learner, 3)
    state = learner.state_dict()
    twin = _learner(seed=99, **options)
    twin.load_state_dict(state)
    contexts = np.random.default_rng(7).uniform(-1, 1, (10, 2))
    np.testing.assert_array_equal(twin.ask(contexts), learner.ask(contexts))
    returns = -np.arange(10.0)
    for agent in (learner, twin):
        agent.tell(_batch(squash(np.zeros((10, N))), returns))
    np.testing.assert_array_equal(twin.policy_actions(contexts), learner.policy_actions(contexts))
    np.testing.assert_allclose(policy_from_state(learner.state_dict(), contexts), learner.policy_actions(contexts),
                               atol=1e-12)


_EXTRAPOLATIONS: dict[tuple, tuple[float, float, np.ndarray]] = {}


def _extrapolation(seed: int, **options) -> tuple[float, float, np.ndarray]:
    """Trained 60 updates on ``s in [-1, 1]^2`` (length 0, epsilon 0.2, ``options``): the held-out loss inside, the
    loss on ``|s_i| in [1.2, 1.6]`` and the KLs ``[60]``. Run once per options and seed in this module: the two
    extrapolation tests share the Adam-fitted linear arm (``linear_prior`` is read by the ridge fit only). The nine
    runs take ~25 CPU s, so both tests are in the slow set; the default set runs the linear and the ridge-fitted
    means through ``test_resume_is_exact_and_the_state_gives_the_policy`` and
    ``test_the_affine_part_is_each_dimensions_weighted_least_squares_fit``."""
    key = (seed, tuple(sorted(options.items())))
    if key not in _EXTRAPOLATIONS:
        learner = _learner(seed=seed, length=0.0, epsilon=0.2, **options)
        rng = np.random.default_rng(100 + seed)
        beyond = rng.uniform(1.2, 1.6, (50, 2)) * rng.choice([-1, 1], (50, 2))
        _, inside, kls = _run(learner, 60, seed=seed)
        _EXTRAPOLATIONS[key] = (inside, np.mean(np.sum((learner.policy_actions(beyond) - _target(beyond)) ** 2,
                                                       axis=1)), kls)
    return _EXTRAPOLATIONS[key]


@pytest.mark.slow
def test_the_linear_part_carries_the_mean_beyond_the_contexts_seen():
    """Trained on ``s in [-1, 1]^2``, judged on ``|s_i| in [1.2, 1.6]``: the mean with a linear part extrapolates the
    linear optimum better than the MLP alone (whose tanh units flatten), and fits the seen contexts as well."""
    plain = np.array([_extrapolation(seed, linear=False)[:2] for seed in range(3)])
    linear = np.array([_extrapolation(seed, linear=True)[:2] for seed in range(3)])
    assert linear[:, 1].mean() < 0.95 * plain[:, 1].mean()
    assert linear[:, 0].mean() < 1.2 * plain[:, 0].mean()
    with pytest.raises(ValueError, match="linear"):                     # a state of the other mean is refused
        _learner(linear=True).load_state_dict(_learner().state_dict())


@pytest.mark.slow
def test_the_ridge_fitted_affine_part_extrapolates_further_than_the_adam_fitted_one():
    """The same toy as above: the affine part fitted in closed form (``linear_fit="ridge"``) extrapolates the linear
    optimum better than the linear part fitted by Adam, and fits the seen contexts at least as well."""
    runs = {"adam": [_extrapolation(seed, linear=True) for seed in range(3)],
            "ridge": [_extrapolation(seed, linear=True, linear_fit="ridge", linear_prior=1.0) for seed in range(3)]}
    for _, _, kls in runs["adam"] + runs["ridge"]:
        assert np.all(kls <= 0.2 + 1e-9)                                  # the closed-form step obeys the bound
    adam, ridge = (np.array([run[:2] for run in runs[fit]]) for fit in ("adam", "ridge"))
    assert ridge[:, 1].mean() < 0.9 * adam[:, 1].mean()
    assert ridge[:, 0].mean() < adam[:, 0].mean()
    with pytest.raises(ValueError, match="affine"):                     # a state of the other linear part is refused
        _learner(linear=True, linear_fit="ridge").load_state_dict(_learner(linear=True).state_dict())


def test_the_affine_part_is_each_dimensions_weighted_least_squares_fit():
    """Samples that are an exact affine function of the context, equally weighted, and a negligible prior: the
    closed-form fit recovers the offset and the gains exactly; with one dimension's weight on two samples only,
    that dimension's fit passes through those two (a weighted fit per dimension, not one shared weighting)."""
    learner = _learner(linear=True, linear_fit="ridge", linear_prior=1e-9)
    rng = np.random.default_rng(3)
    contexts = rng.uniform(-1, 1, (30, 2))
    offset, gains = rng.normal(size=N), rng.normal(size=(N, 2))
    samples = offset + contexts @ gains.T
    contexts_t = torch.as_tensor(contexts)
    with torch.no_grad():
        start = learner.policy.mean(contexts_t)
    learner._fit_affine(contexts_t, torch.as_tensor(samples), np.full((1, 30), 1 / 30), start)
    fitted = learner.policy.affine.detach().numpy()
    np.testing.assert_allclose(fitted[:, 0] + learner.policy.u0.numpy(), offset, atol=1e-6)    # u0: the start
    np.testing.assert_allclose(fitted[:, 1:], gains, atol=1e-6)
    weights = np.full((N, 30), 1 / 30)
    weights[0] = 0.0
    weights[0, :3] = 1 / 3
    noisy = samples + rng.normal(0, 0.1, samples.shape)
    with torch.no_grad():
        start = learner.policy.mean(contexts_t)
    learner._fit_affine(contexts_t, torch.as_tensor(noisy), weights, start)
    with torch.no_grad():
        fitted_mean = learner.policy.mean(contexts_t).numpy()
    np.testing.assert_allclose(fitted_mean[:3, 0], noisy[:3, 0], atol=1e-6)      # three points, three unknowns
    assert np.abs(fitted_mean[3:, 0] - noisy[3:, 0]).max() > 1e-3


def test_bad_options_and_inputs_raise_clear_errors():
    with pytest.raises(ValueError, match="epsilon"):
        _learner(epsilon=0.0)
    with pytest.raises(ValueError, match="rank"):
        _learner(rank=-1)
    with pytest.raises(ValueError, match="credit"):
        _learner(credit="stepwise")
    with pytest.raises(ValueError, match="baseline"):
        _learner(baseline="mlp")
    with pytest.raises(ValueError, match="history"):
        _learner(baseline="network", history=0)
    with pytest.raises(ValueError, match="linear_fit"):
        _learner(linear_fit="ridge")                                     # there is no linear part to fit
    with pytest.raises(ValueError, match="linear_fit"):
        _learner(linear=True, linear_fit="lstsq")
    with pytest.raises(ValueError, match="linear_prior"):
        _learner(linear=True, linear_fit="ridge", linear_prior=0.0)
    networked = _learner(baseline="network")
    _run(networked, 2)
    with pytest.raises(ValueError, match="state"):
        _learner().load_state_dict(networked.state_dict())
    with pytest.raises(ValueError, match="space"):
        make_learner("bbrl", np.zeros(N), 10, np.random.default_rng(0))
    learner = _learner()
    with pytest.raises(ValueError, match="observations"):
        learner.ask(None)
    with pytest.raises(ValueError, match="observations"):
        learner.ask(np.zeros((10, 3)))
    with pytest.raises(RuntimeError, match="ask"):
        learner.tell(_batch(np.zeros((10, N)), np.zeros(10)))


def test_per_step_credit_judges_a_weight_by_the_costs_from_when_it_acts():
    """Sample 0 is the cheaper episode, sample 1 is cheaper from step 3 on: a dimension active only at step 0
    prefers sample 0, one active only at step 3 prefers sample 1, one never active gets the episode weights."""
    traces = np.array([[0.0, 0.0, 0.0, 1.5], [1.0, 1.0, 0.0, 0.0], [0.5, 0.5, 0.5, 0.5]])
    costs = traces.sum(axis=1)
    activation = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0]])   # [T, n]
    per_dimension, episode = sample_weights(costs, traces, np.zeros((3, 1)), activation, h=10.0, ridge=1.0)
    np.testing.assert_allclose(per_dimension.sum(axis=1), 1.0)
    assert per_dimension[0, 0] > 0.9 and per_dimension[1, 1] > 0.9
    np.testing.assert_allclose(per_dimension[2], episode)
    assert episode.argmax() == 0
    only_episode, _ = sample_weights(costs, None, np.zeros((3, 1)), activation, h=10.0, ridge=1.0)
    assert only_episode.shape == (1, 3)


SEGMENT_DIMS = 32
SEGMENT_OFFSETS = 0.3 * np.random.default_rng(7).standard_normal(SEGMENT_DIMS)


def _segment_traces(actions, contexts):
    """``[k, n]`` per-step costs: dimension ``i`` acts at step ``i`` only, and the context's sign decides which half
    of the steps is judged (the first where ``s > 0``), each judged step costing ``(a_i - 0.4 - 0.3 s - o_i)²``."""
    first_half = np.arange(SEGMENT_DIMS) < SEGMENT_DIMS // 2
    judged = np.where(first_half, (contexts[:, 0] > 0)[:, None], (contexts[:, 0] <= 0)[:, None])
    return judged * (actions - (0.4 + 0.3 * contexts + SEGMENT_OFFSETS)) ** 2


def _learn_segments(seed, credit, random_returns=False, updates=30):
    """The held-out cost before and after ``updates`` updates of 10 rollouts, and the largest KL of an update."""
    space = SearchSpace({"periodic": slice(0, SEGMENT_DIMS)}, 1, np.zeros(1), np.ones(1),
                        time_weights=np.eye(SEGMENT_DIMS))
    learner = make_learner("bbrl", np.zeros(SEGMENT_DIMS), 10, np.random.default_rng(seed),
                           {"credit": credit, "rough": 0.5, "epsilon": 0.2}, space=space)
    rng = np.random.default_rng(1000 + seed)
    held_out = rng.uniform(-1, 1, (200, 1))

    def cost():
        return float(np.mean(_segment_traces(learner.policy_actions(held_out), held_out).sum(axis=1)))

    before, kls = cost(), []
    for _ in range(updates):
        contexts = rng.uniform(-1, 1, (10, 1))
        actions = learner.ask(contexts)
        traces = _segment_traces(actions, contexts)
        returns = rng.standard_normal(10) if random_returns else -traces.sum(axis=1)
        learner.tell(_batch(actions, returns, traces))
        kls.append(learner.last_kl)
    return before, cost(), max(kls)


@pytest.mark.parametrize("seed", [0, pytest.param(1, marks=pytest.mark.slow)])        # seed 1: in the slow set
def test_per_step_credit_learns_the_segment_the_context_judges(seed):
    """Only one half of the movement is judged and the context decides which: crediting each weight with the cost
    from the step it acts at learns the rough per-step target in both halves well below what one credit per
    episode reaches in as many updates, every update inside the trust region; random returns learn nothing."""
    before, step, step_kl = _learn_segments(seed, "step")
    _, episode, episode_kl = _learn_segments(seed, "episode")
    assert step < 0.15 * before
    assert step < 0.75 * episode
    assert max(step_kl, episode_kl) <= 0.2 + 1e-9
    _, control, _ = _learn_segments(seed, "episode", random_returns=True)
    assert control > 0.5 * before


def test_remaining_step_weighting_lets_the_steps_that_see_most_of_the_episode_count_most():
    """A dimension active at every step; sample 0 is the cheapest episode, sample 1 the cheapest from step 1 on:
    averaged by activation the late steps outvote the first, averaged by ``T - t`` (``"remaining"``) sample 0 gains
    weight, and a dimension active only at the last step is judged the same either way."""
    traces = np.array([[0.0, 0.0, 0.0, 1.5], [1.0, 1.0, 0.0, 0.0], [0.5, 0.5, 0.5, 0.5]])
    activation = np.zeros((4, N))
    activation[:, 0] = 1.0
    activation[3, 1] = 1.0
    space = SearchSpace({"all": slice(0, N)}, 1, np.zeros(2), np.ones(2), activation)
    weights = {}
    for weighting in ("activation", "remaining"):
        learner = make_learner("bbrl", np.zeros(N), 3, np.random.default_rng(0), {"step_weighting": weighting},
                               space=space)
        data = {"costs": traces.sum(axis=1), "traces": traces, "contexts": np.zeros((3, 2))}
        weights[weighting] = learner._sample_weights(data, None)[0]
    assert weights["activation"][0].argmax() == 1
    assert weights["remaining"][0, 0] > weights["activation"][0, 0] + 0.1
    np.testing.assert_allclose(weights["remaining"][1], weights["activation"][1])
    with pytest.raises(ValueError, match="step_weighting"):
        _learner(step_weighting="late")


def test_a_predicted_context_cost_lets_the_best_sample_of_an_expensive_context_count():
    """Contexts near 0 cost 10 more whatever the action (a cost no linear function of the context explains);
    among them, sample 2 acted best. Over the ridge alone their samples get no weight; with the context's cost
    predicted, sample 2 gets the most and outweighs the worse samples of the cheap contexts."""
    contexts = np.array([[-1.0], [-0.6], [0.0], [0.0], [0.6], [1.0]])
    quality = np.array([2.0, 3.0, 0.5, 4.0, 1.0, 2.5])               # the action's own cost
    spike = np.where(np.abs(contexts[:, 0]) < 0.3, 10.0, 0.0)
    costs = quality + spike
    ridge_only, _ = sample_weights(costs, None, contexts, None, h=10.0, ridge=1.0)
    predicted, _ = sample_weights(costs, None, contexts, None, h=10.0, ridge=1.0, predicted=spike[:, None])
    assert ridge_only[0, 2] < 1e-3
    assert predicted[0, 2] == predicted[0].max() and predicted[0, 3] < predicted[0, 1]


def test_the_network_baseline_learns_a_cost_no_linear_function_of_the_context_gives():
    """The toy's cost plus 5 wherever |s_0| > 0.6 (symmetric: no linear function of the context sees it): after
    30 updates the baseline network predicts most of the jump on held-out contexts."""
    learner = _learner(baseline="network", history=10, credit="episode")
    rng = np.random.default_rng(3)
    for _ in range(30):
        contexts = rng.uniform(-1, 1, (10, 2))
        actions = learner.ask(contexts)
        costs = np.sum((actions - _target(contexts)) ** 2, axis=1) + 5.0 * (np.abs(contexts[:, 0]) > 0.6)
        learner.tell(_batch(actions, -costs))
    probe = np.random.default_rng(8).uniform(-1, 1, (400, 2))
    with torch.no_grad():
        values = learner.value(torch.as_tensor(probe)).numpy()[:, 0]
    outer = np.abs(probe[:, 0]) > 0.6
    assert values[outer].mean() - values[~outer].mean() > 3.0            # the jump is 5; a linear fit sees ~0


def test_a_saved_config_may_hold_what_bbrl_fixes_at_its_fixed_value_only():
    """``config.json`` of a run holds every setting it ran with: a name bbrl no longer takes as an option is read
    where it holds the value bbrl always runs with, and is an error naming it where it holds another."""
    saved = {**BBRLConfig(epsilon=1.0).to_dict(), "groups": [], "value_ridge": 1, "replay": 0.0,
             "replay_temperature": 0.3, "replay_size": 100}
    assert BBRLConfig.from_dict(saved, "bbrl") == BBRLConfig(epsilon=1.0)
    with pytest.raises(ValueError, match=r"bbrl\.replay: not an option of bbrl, which always runs with replay = 0\.0"):
        BBRLConfig.from_dict({**saved, "replay": 0.3}, "bbrl")
    with pytest.raises(ValueError, match=r"bbrl\.groups"):
        BBRLConfig.from_dict({"groups": ["amplitude"]}, "bbrl")
    with pytest.raises(ValueError, match=r"unknown option\(s\) \['replays'\]"):
        BBRLConfig.from_dict({"replays": 0.0}, "bbrl")


def test_antithetic_sampling_mirrors_each_perturbation_on_a_shared_context():
    learner = _learner(antithetic=True)
    np.testing.assert_array_equal(learner.choose_seeds(np.arange(100, 110)), np.repeat(np.arange(100, 105), 2))
    contexts = np.repeat(np.random.default_rng(2).uniform(-1, 1, (5, 2)), 2, axis=0)
    u = unsquash(learner.ask(contexts))
    mean = unsquash(learner.policy_actions(contexts))
    np.testing.assert_allclose(u[0::2] + u[1::2], 2 * mean[0::2], atol=1e-9)
    assert np.all(np.abs(u[0::2] - mean[0::2]) > 0)
    with pytest.raises(ValueError, match="observations"):
        learner.ask(np.random.default_rng(3).uniform(-1, 1, (10, 2)))
    with pytest.raises(ValueError, match="rollouts"):
        make_learner("bbrl", np.zeros(N), 9, np.random.default_rng(0), {"antithetic": True}, space=_space())


def test_a_pairs_mean_cost_judges_its_samples_whatever_the_context_costs():
    """Pair 0 (a context that costs 10 more) and pair 1 differ by the same 2 between their samples: paired, the
    better sample of each gets the same, largest weight; over the ridge alone the expensive pair gets none."""
    contexts = np.array([[0.0], [0.0], [0.5], [0.5]])
    costs = np.array([10.0, 12.0, 0.0, 2.0])
    paired, _ = sample_weights(costs, None, contexts, None, h=10.0, ridge=1.0, paired=True)
    ridge_only, _ = sample_weights(costs, None, contexts, None, h=10.0, ridge=1.0)
    assert paired[0, 0] == pytest.approx(paired[0, 2]) and paired[0, 0] == paired[0].max()
    assert ridge_only[0, 0] < 1e-3
    with pytest.raises(ValueError, match="pairs"):
        sample_weights(costs[:3], None, contexts[:3], None, h=10.0, ridge=1.0, paired=True)


def test_antithetic_learns_the_contextual_quadratic_and_resumes_exactly():
    learner = _learner(antithetic=True, length=0.0, epsilon=0.2)
    rng = np.random.default_rng(11)
    held_out = rng.uniform(-1, 1, (50, 2))

    def loss():
        return np.mean(np.sum((learner.policy_actions(held_out) - _target(held_out)) ** 2, axis=1))

    before = loss()
    for _ in range(40):
        contexts = np.repeat(rng.uniform(-1, 1, (5, 2)), 2, axis=0)
        actions = learner.ask(contexts)
        learner.tell(_batch(actions, -np.sum((actions - _target(contexts)) ** 2, axis=1)))
    assert loss() < 0.4 * before
    twin = _learner(seed=5, antithetic=True, length=0.0, epsilon=0.2)
    twin.load_state_dict(learner.state_dict())
    contexts = np.repeat(held_out[:5], 2, axis=0)
    np.testing.assert_array_equal(twin.ask(contexts), learner.ask(contexts))


def test_the_kl_with_per_context_scales_matches_the_full_covariances():
    rng = np.random.default_rng(4)
    n, k = 4, 3
    factors = [rng.standard_normal((n, n)) + 3 * np.eye(n) for _ in range(2)]
    covs = [f @ f.T for f in factors]
    means = [rng.standard_normal((k, n)) for _ in range(2)]
    scales = [rng.uniform(-0.5, 0.5, k) for _ in range(2)]
    got = gaussian_kl(*[torch.as_tensor(x) for x in (means[0], np.linalg.cholesky(covs[0]), means[1],
                                                      np.linalg.cholesky(covs[1]), scales[0], scales[1])]).numpy()
    for row in range(k):
        old, new = np.exp(2 * scales[0][row]) * covs[0], np.exp(2 * scales[1][row]) * covs[1]
        diff = means[1][row] - means[0][row]
        expected = 0.5 * (np.trace(np.linalg.solve(new, old)) + diff @ np.linalg.solve(new, diff) - n
                          + np.log(np.linalg.det(new) / np.linalg.det(old)))
        assert got[row] == pytest.approx(expected, rel=1e-9)


def test_a_per_context_scale_narrows_the_exploration_where_the_cost_is_sharp():
    """Where s_0 < 0 the cost punishes every step from the target; where s_0 > 0 every action costs the same:
    the exploration narrows in the first half of the contexts and not in the second, within the trust region."""
    learner = _learner(context_scale=True, length=0.0, epsilon=0.2)
    rng = np.random.default_rng(9)
    kls = []
    for _ in range(30):
        contexts = rng.uniform(-1, 1, (10, 2))
        actions = learner.ask(contexts)
        sharp = np.sum((actions - _target(contexts)) ** 2, axis=1)
        learner.tell(_batch(actions, -np.where(contexts[:, 0] < 0, sharp, 0.0)))
        kls.append(learner.last_kl)
    probe = np.random.default_rng(2).uniform(-1, 1, (200, 2))
    with torch.no_grad():
        log_scale = learner.policy.log_scale(torch.as_tensor(probe)).numpy()
    assert log_scale[probe[:, 0] < -0.3].mean() < log_scale[probe[:, 0] > 0.3].mean() - 0.1
    assert np.all(np.array(kls) <= 0.2 + 1e-9)
    contexts = rng.uniform(-1, 1, (10, 2))
    np.testing.assert_allclose(policy_from_state(learner.state_dict(), contexts), learner.policy_actions(contexts),
                               atol=1e-12)
    twin = _learner(seed=3, context_scale=True, length=0.0, epsilon=0.2)
    twin.load_state_dict(learner.state_dict())
    np.testing.assert_array_equal(twin.ask(contexts), learner.ask(contexts))
    with pytest.raises(ValueError, match="state"):
        _learner().load_state_dict(learner.state_dict())


def test_sigma_factors_widen_the_named_groups_exploration():
    learner = _learner(sigma_factors="amplitude=3")
    with torch.no_grad():
        sigma = torch.sqrt(torch.diagonal(learner.policy.covariance(learner.config.min_sigma))).numpy()
    np.testing.assert_allclose(sigma[N - 2:], 0.9, rtol=1e-9)
    np.testing.assert_allclose(sigma[: N - 2], 0.3, rtol=1e-9)
    samples = unsquash(learner.ask(np.zeros((10, 2))))
    assert np.std(samples[:, N - 2:]) > 2 * np.std(samples[:, : N - 2])
    for bad in ("amplitude=0", "amplitude", "sweep=2"):
        with pytest.raises(ValueError, match="sigma_factors"):
            _learner(sigma_factors=bad)
