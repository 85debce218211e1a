"""The oracular particle filter: bounded, calibrated, ambiguous only where the world is,
in both worlds."""

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

from hippo_probe.baselines import particle_filter, path_integration
from hippo_probe.baselines.calibration import filter_ranks, posterior_ranks
from hippo_probe.tasks import TASKS, make_trials, task_config
from hippo_probe.world import WORLDS, NoiseModel, random_arena, regular_polygon


def test_error_stays_bounded_while_pi_drifts():
    batch = make_trials("generalized", 16, "test", 0)
    pf = particle_filter(batch, 300).error(batch).mean(axis=1)
    pi = path_integration(batch).error(batch).mean(axis=1)
    early, late = slice(25, 75), slice(450, 500)            # 10-30 s and 180-200 s
    assert pi[late].mean() > 2 * pi[early].mean()           # PI drifts ...
    assert pf[late].mean() < 1.3 * pf[early].mean()         # ... the PF does not
    assert pf.max() < 0.1                                   # within 10 cm all along


# ranks 20 s apart, so that successive ranks of a trial are nearly independent
CALIBRATION_STEPS = np.arange(25, 500, 50)


def assert_calibrated(ranks):
    """Uniform ranks: KS, and the 90% region (ranks below 0.9) holding the truth 90% of
    the time."""
    for name, rank in ranks.items():
        assert stats.kstest(rank, "uniform").pvalue > 0.01, name
        assert abs(np.mean(rank < 0.9) - 0.9) < 0.05, name


# 150 trials of the localization filter take minutes. Its calibration at the default 2,000
# particles comes from the kernel after resampling (ParticleFilterConfig.
# unknown_start_regularization = 0.3): plain, its 90% region held 0.867 here (KS p 0.001).
@pytest.mark.parametrize("task, world", [
    pytest.param(task, world, marks=pytest.mark.slow)
    if (task, world) == ("localization", "darkness") else (task, world)
    for world in WORLDS for task in TASKS])
def test_calibrated(task, world):
    """The rank of the truth among the particles is uniform: position in both worlds,
    and the heading drift in the darkness world (default particle counts). 150 trials
    put the coverage of the 90% region within about 0.01 of the filter's (60 did not:
    0.850-0.912 where 150 trials read 0.875-0.898)."""
    batch = make_trials(task, 150, "validation", 0, world=world)
    res = particle_filter(batch, keep=CALIBRATION_STEPS)
    ranks = posterior_ranks(res, batch)
    if world == "compass":
        assert (res.particle_drifts == 0).all() and (res.drift_sd == 0).all()
        del ranks["drift"]
    assert_calibrated(ranks)


@pytest.mark.slow
def test_converged_localization_filter_calibrated():
    """At 20,000 particles the plain localization filter of the darkness world (no kernel
    after resampling) is calibrated: its model, the contact's outlier floor included, is
    right, and what the default's kernel removes at 2,000 particles is Monte Carlo
    error."""
    from hippo_probe.baselines.config import BaselineConfig, ParticleFilterConfig

    batch = make_trials("localization", 60, "validation", 0)
    plain = BaselineConfig(particle_filter=ParticleFilterConfig(unknown_start_regularization=0))
    ranks = filter_ranks(batch, 20_000, keep=CALIBRATION_STEPS, chunk=20, baseline=plain)
    assert_calibrated({k: ranks[k].ravel() for k in ("mahalanobis", "projection", "drift")})


def test_filter_ranks_in_chunks_equal_one_run():
    """Running the filter on chunks of trials (to bound memory) changes no Mahalanobis or
    drift rank: each trial's random numbers depend on its index only."""
    keep = [100, 300, 499]
    batch = make_trials("generalized", 5, "validation", 0)
    whole = posterior_ranks(particle_filter(batch, 200, keep=keep), batch)
    chunked = filter_ranks(batch, 200, keep=keep, chunk=2)
    for name in ("mahalanobis", "drift"):
        assert chunked[name].shape == (3, 5)
        np.testing.assert_array_equal(chunked[name].ravel(), whole[name])
    assert chunked["mean"].shape == (3, 5, 2) and chunked["cov"].shape == (3, 5, 3)
    with pytest.raises(ValueError, match="chunk"):
        filter_ranks(batch, 200, keep=keep, chunk=0)


def test_outlier_floor_near_walls_only_where_a_contact_could_happen():
    """At a first contact under a broad posterior (start unknown), the outlier floor given
    to every particle (``outlier_near_walls=False``, the earlier contact model)
    keeps particles far inside the arena; near walls only (the default), it goes only to
    particles whose step could have reached a wall (start and end distances to their
    nearest walls summing to at most ``2 touch_range + max_speed * network_dt``, so no
    particle ending farther than that from every wall keeps weight)."""
    from hippo_probe.baselines.config import BaselineConfig, ContactModelConfig
    from hippo_probe.world.arena import wall_distance

    batch = make_trials("localization", 6, "validation", 0)
    first = batch.contact.argmax(axis=0)
    assert batch.contact.any(axis=0).all()
    world = batch.config.world
    reach = 2 * world.sensors.touch_range + world.motion.max_speed * world.motion.network_dt
    beyond = {}
    for near in (False, True):
        res = particle_filter(batch, 500, keep=np.unique(first), baseline=BaselineConfig(
            contact=ContactModelConfig(outlier_near_walls=near)))
        steps = list(res.attrs["kept_steps"])
        mass = []
        for b in range(len(batch)):
            k = steps.index(first[b])
            far = wall_distance(batch.arena_vertices[b], res.particles[k, b])[0] > reach
            mass.append(res.particle_weights[k, b][far].sum())
        beyond[near] = np.array(mass)
    assert (beyond[True] == 0).all()
    assert beyond[False].max() > 0.01        # the floor everywhere leaves mass out there


def test_split_proposals_keep_more_distinct_particles_through_a_contact():
    """With one move per particle, the sharp contact likelihood leaves few particles
    carrying the posterior (effective sample size); with ``contact_proposals`` children
    per particle, the particles kept after the contact are many more distinct ones, and
    the error does not suffer."""
    from hippo_probe.baselines.config import BaselineConfig, ParticleFilterConfig

    batch = make_trials("generalized", 6, "validation", 0)
    steps = [100 + int(np.argmax(batch.contact[100:, b])) for b in range(len(batch))]
    assert all(batch.contact[t, b] for b, t in enumerate(steps))
    results = {m: particle_filter(batch, 300, keep=steps, baseline=BaselineConfig(
        particle_filter=ParticleFilterConfig(contact_proposals=m))) for m in (1, 8)}
    kept = results[1].attrs["kept_steps"]
    ess, distinct = [], []
    for b, t in enumerate(steps):
        k = kept.index(t)
        ess.append(1 / np.sum(results[1].particle_weights[k, b] ** 2))
        distinct.append(np.unique(results[8].particles[k, b, :, 0]).size)
    assert np.mean(distinct) > 2 * np.mean(ess)
    errors = {m: r.error(batch).mean() for m, r in results.items()}
    assert errors[8] < 1.1 * errors[1]


def test_darkness_filter_tracks_the_drift():
    batch = make_trials("generalized", 20, "test", 0)
    res = particle_filter(batch)
    late = slice(400, None)
    error = np.abs(res.drift_mean - batch.heading_drift)[late]
    assert np.median(error) < 0.5 * np.median(np.abs(batch.heading_drift[late]))
    # the reported s.d. is the size of the error (calibrated within sampling error)
    assert 0.7 < np.sqrt(np.mean(error ** 2) / np.mean(res.drift_sd[late] ** 2)) < 1.3


def test_without_drift_the_darkness_filter_is_the_compass_filter():
    """The darkness world with its drift switched off makes the compass world's trials,
    and the filter built for it (drift hypotheses that never move) gives the compass
    filter's results."""
    config = task_config("generalized")
    quiet = replace(config, world=replace(config.world,
                                          noise=replace(config.world.noise, heading_drift=0)))
    still = make_trials("generalized", 5, "test", 0, config=quiet)
    compass = make_trials("generalized", 5, "test", 0, world="compass")
    assert np.array_equal(still.inputs, compass.inputs) and still.world.name == "darkness"
    a, b = particle_filter(still, 300), particle_filter(compass, 300)
    np.testing.assert_allclose(a.estimate, b.estimate, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.cov, b.cov, rtol=0, atol=1e-12)


@pytest.mark.parametrize("world", WORLDS)
def test_a_batch_of_another_world_gets_a_filter_of_that_world(world):
    """A noiseless world: the filter built from the batch's own world has no motion noise
    and follows the path to millimetres; one built from the default world would spread
    its particles by centimetres."""
    exact = task_config("generalized", world=replace(
        task_config("generalized", world).world, noise=NoiseModel.noiseless()))
    batch = make_trials("generalized", 4, "test", 0, config=exact)
    res = particle_filter(batch, 100)
    assert res.error(batch).max() < 2e-3
    assert np.sqrt(res.cov[..., :2].sum(axis=-1)).max() < 1e-6
    default = make_trials("generalized", 4, "test", 0, world=world)
    assert particle_filter(default, 100).error(default).mean() > 0.01


def test_unknown_heading_in_a_regular_polygon_cannot_tell_its_copies_apart(make_trials_in):
    """Darkness world, start and start heading unknown (drift hypotheses uniform): a
    regular polygon looks the same after any rotation by a multiple of 2 pi / V, so the
    exact posterior puts equal mass on the V rotated copies of the truth. A finite
    particle filter lets that mass wander among the copies (resampling noise; most
    trials end mostly on one copy), but which copy is chance: the truth's copy gets
    about 1 / V of the mass on average, while an oriented rat picks it."""
    n_vertices, n_steps = 5, 100                                          # 40 s
    arena = regular_polygon(n_vertices, 0.4).vertices
    batch = make_trials_in(arena, 12, seed=2, n_steps=n_steps)
    last = n_steps - 1
    truth = batch.position[last]
    turns = 2 * np.pi * np.arange(n_vertices) / n_vertices
    c, s = np.cos(turns)[:, None], np.sin(turns)[:, None]
    copies = np.stack([c * truth[None, :, 0] - s * truth[None, :, 1],
                       s * truth[None, :, 0] + c * truth[None, :, 1]], axis=-1)  # (V, B, 2)

    def mass_on_copies(res):
        p, w = res.particles[0], res.particle_weights[0]                 # (B, N, 2), (B, N)
        distance = np.linalg.norm(p[None] - copies[:, :, None], axis=-1)   # (V, B, N)
        near = distance.min(axis=0) < 0.1
        nearest = np.argmin(distance, axis=0)
        mass = np.stack([np.sum(w * near * (nearest == k), axis=-1)
                         for k in range(n_vertices)])                    # (V, B)
        return mass

    lost = mass_on_copies(particle_filter(batch, 2000, start="unknown", oriented=False,
                                          keep=[last]))
    assert np.median(lost.sum(axis=0)) > 0.7         # the posterior sits on the copies ...
    assert lost[0].mean() < 0.45                     # ... but not on the truth's (1/V = 0.2)
    assert np.mean(np.argmax(lost, axis=0) == 0) < 0.6
    oriented = mass_on_copies(particle_filter(batch, 2000, start="unknown", keep=[last]))
    assert np.median(oriented[0]) > 0.7


def test_ambiguous_where_the_world_is(make_trials_in):
    """Compass world: with the allocentric frame given, only a translation leaves every
    input unchanged: in a long corridor the posterior stays spread along its axis (until
    an end is touched) while contacts pin the cross-axis position; a compact asymmetric
    arena localizes."""
    corridor = np.array([[-5.0, -0.15], [5.0, -0.15], [5.0, 0.15], [-5.0, 0.15]])
    batch = make_trials_in(corridor, 8, seed=1, n_steps=75, world="compass")  # 30 s
    res = particle_filter(batch, 500, start="unknown")
    sd_along, sd_across = np.sqrt(res.cov[-1, :, 0]), np.sqrt(res.cov[-1, :, 1])
    assert np.median(sd_along) > 1.0
    assert np.median(sd_across) < 0.03

    arena = random_arena(np.random.default_rng(3), 10, 0.6).vertices
    batch = make_trials_in(arena, 8, seed=1, n_steps=75, world="compass")
    res = particle_filter(batch, 500, start="unknown")
    sd = np.sqrt(res.cov[-1, :, 0] + res.cov[-1, :, 1])
    assert np.median(sd) < 0.1
    assert np.median(res.error(batch)[-1]) < 0.1


def test_identical_seeds_identical_results():
    batch = make_trials("localization", 6, "test", 0)
    a = particle_filter(batch, 200, threads=2)
    b = particle_filter(batch, 200, threads=1)
    part = particle_filter(batch.select([4, 5]), 200)
    assert np.array_equal(a.estimate, b.estimate) and np.array_equal(a.cov, b.cov)
    assert np.array_equal(a.estimate[:, 4:], part.estimate)   # per-trial random streams
    other = make_trials("localization", 6, "test", 1)
    assert not np.array_equal(a.estimate, particle_filter(other, 200).estimate)


def test_results_and_particles_are_consistent():
    batch = make_trials("generalized", 3, "test", 0)
    keep = [0, 10, 499]
    res = particle_filter(batch, 150, keep=keep)
    assert res.particles.shape == (3, 3, 150, 2)
    assert np.allclose(res.particle_weights.sum(axis=-1), 1.0)
    mean = np.einsum("kbn,kbnd->kbd", res.particle_weights, res.particles)
    assert np.allclose(mean, res.mean[keep])
    # the generalized estimate is the start-relative mean (start known)
    assert np.allclose(res.estimate, res.mean - batch.start[None])
    assert (res.cov[..., 0] >= 0).all() and (res.cov[..., 1] >= 0).all()
    assert (res.cov[..., 2] ** 2 <= res.cov[..., 0] * res.cov[..., 1] + 1e-15).all()


def test_kernel_after_resampling_widens_by_its_bandwidth_and_stays_in_the_arena():
    """The regularization kernel moves equally weighted particles by h L z, L L^T their
    covariance: the mean stays, the covariance grows by h^2 times itself, and exactly the
    moves that would leave the arena are undone."""
    from hippo_probe.baselines.contact import wall_table
    from hippo_probe.baselines.particle_filter import _regularize

    # far from every wall (|x|, |y| < 2.1 m, 9 s.d.), so that no move is undone
    walls = wall_table(regular_polygon(4, 3.0, np.pi / 4).vertices)
    rng = np.random.default_rng(0)
    n, h = 200_000, 0.5
    cov = np.array([[0.04, 0.01, 0.002], [0.01, 0.02, 0.003], [0.002, 0.003, 0.01]])
    before = rng.multivariate_normal([0.1, -0.1, 0.2], cov, n)
    x, y, eta = (np.ascontiguousarray(c) for c in before.T)
    _regularize(np.random.default_rng(1), x, y, eta, h, walls, 0.0,
                *[np.empty(n) for _ in range(6)])
    after = np.stack([x, y, eta])
    np.testing.assert_allclose(after.mean(axis=1), before.mean(axis=0), atol=0.003)
    # every entry of the change against h^2 Sigma (0.0005-0.01), sampling error ~6e-5
    np.testing.assert_allclose(np.cov(after) - np.cov(before.T), h * h * np.cov(before.T),
                               rtol=0, atol=2.5e-4)
    # near a wall with a wide kernel: the moves that would cross it are undone, the rest
    # are kept
    walls = wall_table(regular_polygon(4, 1.0, np.pi / 4).vertices)   # |x|, |y| < 0.7071
    m = 2000
    x = np.random.default_rng(3).uniform(0.55, 0.70, m)
    y = np.random.default_rng(4).uniform(-0.3, 0.3, m)
    eta = np.zeros(m)
    x0, y0 = x.copy(), y.copy()
    _regularize(np.random.default_rng(2), x, y, eta, 1.0, walls, 0.0,
                *[np.empty(m) for _ in range(6)])
    moved = (x != x0) | (y != y0)
    assert (np.abs(x) < 0.7071).all() and (np.abs(y) < 0.7071).all()
    assert 0.03 < (~moved).mean() < 0.3         # some proposals cross x = 0.7071, most not
    # the same proposals, replayed: exactly those that would have left were undone
    z = np.random.default_rng(2).standard_normal((m, 3))
    chol = np.linalg.cholesky(np.cov(np.stack([x0, y0]), bias=True))
    px = x0 + chol[0, 0] * z[:, 0]
    py = y0 + chol[1, 0] * z[:, 0] + chol[1, 1] * z[:, 1]
    edge = np.sqrt(0.5)
    np.testing.assert_array_equal(~moved, (np.abs(px) >= edge) | (np.abs(py) >= edge))


def test_kernel_only_where_the_start_is_unknown_and_the_heading_known():
    """By default the kernel runs in the localization filter (start unknown) and not in
    the small-arena ones (start known), nor with the start heading unknown (the drift
    spans the circle); the bandwidth used is in the result's attrs."""
    from hippo_probe.baselines.config import BaselineConfig, ParticleFilterConfig

    loc = make_trials("localization", 2, "validation", 0)
    default = particle_filter(loc, 300)
    plain = particle_filter(loc, 300, baseline=BaselineConfig(
        particle_filter=ParticleFilterConfig(unknown_start_regularization=0)))
    assert default.attrs["regularization"] == 0.3 and plain.attrs["regularization"] == 0
    assert not np.allclose(default.mean, plain.mean)
    assert particle_filter(loc, 300, oriented=False).attrs["regularization"] == 0
    gen = make_trials("generalized", 2, "validation", 0)
    assert particle_filter(gen, 300).attrs["regularization"] == 0


def test_bad_input_is_named():
    batch = make_trials("generalized", 1, "test", 0)
    with pytest.raises(ValueError, match="`n_particles` must be > 0"):
        particle_filter(batch, -5)
    with pytest.raises(ValueError, match="`keep` must hold steps"):
        particle_filter(batch, 10, keep=[500])
    with pytest.raises(ValueError, match="`config` is for task"):
        particle_filter(batch, 10, config=task_config("localization"))
    with pytest.raises(ValueError, match="`n_particles` must be > 0; got 0"):
        particle_filter(batch, 0)
    with pytest.raises(ValueError, match="`threads` must be > 0; got 0"):
        particle_filter(batch, 10, threads=0)          # not silently "every core"
    from hippo_probe.baselines.config import ContactModelConfig, ParticleFilterConfig
    with pytest.raises(ValueError, match="`contact_proposals` must be > 0; got 0"):
        ParticleFilterConfig(contact_proposals=0)
    with pytest.raises(TypeError, match="`outlier_near_walls` must be True or False"):
        ContactModelConfig(outlier_near_walls="yes")
    with pytest.raises(ValueError, match="`regularization` must be >= 0; got -0.1"):
        ParticleFilterConfig(regularization=-0.1)
    with pytest.raises(ValueError, match="`unknown_start_regularization` must be >= 0"):
        ParticleFilterConfig(unknown_start_regularization=-1)


def test_a_filter_configuration_that_disagrees_with_the_batch_is_refused():
    batch = make_trials("generalized", 1, "test", 0)               # darkness
    with pytest.raises(ValueError, match="world.name: given 'compass', batch 'darkness'"):
        particle_filter(batch, 10, config=task_config("generalized", "compass"))
    # the batch's own configuration is accepted
    particle_filter(batch, 10, config=batch.config)


def test_drift_ranks_wrap_around_the_circle():
    """Particles spread across +-pi around a truth near pi: the truth sits mid-posterior
    (rank 0.5), which a plain ordering of the angles would call an extreme (~0 or ~1)."""
    from types import SimpleNamespace

    rng = np.random.default_rng(0)
    n = 2000
    drifts = (np.pi + rng.normal(0, 0.3, n) + np.pi) % (2 * np.pi) - np.pi
    result = SimpleNamespace(
        particles=rng.normal(0, 0.1, (1, 1, n, 2)), particle_weights=np.full((1, 1, n), 1 / n),
        particle_drifts=drifts[None, None], attrs={"kept_steps": [0]})
    batch = SimpleNamespace(position=np.zeros((1, 1, 2)),
                            heading_drift=np.array([[np.pi - 1e-3]]))
    rank = posterior_ranks(result, batch)["drift"]
    assert abs(float(rank[0]) - 0.5) < 0.05


def test_rotation_cosines_and_sines_to_3e7_and_exact_beyond_one_radian():
    """The motion step's vectorized cos/sin: the series below 1 rad (the rotation noise is
    0.18 rad) within 3e-7 of the library; beyond it, the library's own values."""
    from hippo_probe.baselines.particle_filter import _cos_sin

    r = np.r_[np.linspace(-3.5, 3.5, 7001), -1.0, 1.0, np.nextafter(1.0, 0.0), 0.0]
    c, s = np.empty_like(r), np.empty_like(r)
    _cos_sin(r, c, s)
    small = np.abs(r) < 1.0
    assert np.abs(c[small] - np.cos(r[small])).max() < 3e-7
    assert np.abs(s[small] - np.sin(r[small])).max() < 3e-7
    # (the C library's values, as math gives them; NumPy's vector cos may differ by an ulp)
    assert c[~small].tolist() == [math.cos(v) for v in r[~small]]
    assert s[~small].tolist() == [math.sin(v) for v in r[~small]]


def test_intermediate_check_looks_only_at_particles_that_could_touch():
    """The no-contact check inside a step skips particles whose chord point is provably
    beyond the touch range: its likelihoods must be those of checking every particle, bit
    for bit, in several arenas at once (PF-SLAM's blocks), near walls and corners and far
    from them."""
    from hippo_probe.baselines.contact import towards, wall_table
    from hippo_probe.baselines.particle_filter import _intermediate_check, _nearest_walls

    rng = np.random.default_rng(5)
    walls = np.stack([wall_table(random_arena(rng, 10, 0.33).vertices) for _ in range(3)])
    sizes = [400, 0, 700]                                       # an empty block too
    block = np.r_[0, np.cumsum(sizes)].astype(np.int64)
    n = block[-1]
    arena = np.repeat(np.arange(3), sizes).astype(np.int64)
    corner = walls[arena, rng.integers(0, 10, n), :2]
    inner = rng.uniform(-0.3, 0.3, (n, 2))
    end = np.where((np.arange(n) % 2 == 0)[:, None], corner + rng.normal(0, 0.05, (n, 2)),
                   inner)
    start = end - rng.normal(0, 0.04, (n, 2))
    xs, ys, xe, ye = start[:, 0].copy(), start[:, 1].copy(), end[:, 0].copy(), end[:, 1].copy()
    eta = rng.normal(0, 0.2, n)
    touch_range, heading_sd = 0.05, 0.1
    best, nearest, crossings = np.empty(n), np.empty(n), np.empty(n)
    end_distance = np.empty(n)
    for a in range(3):
        lo, hi = block[a], block[a + 1]
        _nearest_walls(walls[a], xe[lo:hi], ye[lo:hi], best[lo:hi], nearest[lo:hi],
                       crossings[lo:hi])
    end_distance[:] = np.sqrt(best)
    for f in (0.5, 0.25, 0.75):
        heading, turn = rng.uniform(-np.pi, np.pi), rng.normal(0, 0.3)
        expected = rng.uniform(0.5, 1.0, n)
        lik = expected.copy()
        xm, ym = xs + f * (xe - xs), ys + f * (ye - ys)
        for a in range(3):
            lo, hi = block[a], block[a + 1]
            _nearest_walls(walls[a], xm[lo:hi], ym[lo:hi], best[lo:hi], nearest[lo:hi],
                           crossings[lo:hi])
        touching = np.flatnonzero(best < touch_range * touch_range)
        assert 50 < touching.size < n - 50                      # both kinds present
        for i in touching:
            expected[i] *= 1.0 - towards(walls[arena[i], int(nearest[i]), 7],
                                         heading - (1.0 - f) * turn - eta[i], heading_sd)
        scratch = [np.empty(n) for _ in range(5)]
        _intermediate_check(f, heading, turn, walls, block, xs, ys, xe, ye, eta, arena,
                            end_distance, touch_range, heading_sd, lik,
                            np.empty(n, np.int64), *scratch)
        assert np.array_equal(lik, expected), f
