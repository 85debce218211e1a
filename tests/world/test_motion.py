"""Motion: the correlated random walk never leaves its arena and follows its config."""

import numba
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hippo_probe.world import (ArenaConfig, MotionConfig, SensorConfig, contains,
                               random_vertices, regular_polygon, sample_uniform,
                               simulate_motion, wall_distance)

SENSORS = SensorConfig()


def every_fine_step(n_steps, **motion):
    """A motion config whose network step is the fine step: every position is sampled."""
    fine_dt = motion.pop("fine_dt", MotionConfig.fine_dt)
    return MotionConfig(fine_dt=fine_dt, network_dt=fine_dt, n_steps=n_steps, **motion)


def clear_starts(verts, rng, clearance):
    """One start per arena, uniform among points at least ``clearance`` from every wall."""
    candidates = np.stack([sample_uniform(v, rng, 64) for v in verts])
    distance, _, _ = wall_distance(verts, candidates)
    first = np.argmax(distance >= clearance, axis=1)
    assert (distance[np.arange(len(verts)), first] >= clearance).all()
    return candidates[np.arange(len(verts)), first]


def run(verts, motion, rng, sensors=SENSORS, starts=None, heading0=None):
    n = len(verts)
    n_fine = motion.n_steps * motion.substeps
    starts = clear_starts(verts, rng, sensors.touch_range) if starts is None else starts
    heading0 = rng.uniform(-np.pi, np.pi, n) if heading0 is None else heading0
    out = simulate_motion(verts, starts, heading0, rng.standard_normal((n, n_fine)),
                          rng.standard_normal((n, n_fine)), motion, sensors)
    return starts, out


def crossings(verts, starts, position, distance, geometry):
    """Number of straight moves between consecutive samples that cut through a wall.

    A move that cuts a wall ends no farther from it than the move's length, so only moves
    ending that close to a wall (``distance``: of each sample to its nearest wall) are
    checked against every wall.
    """
    previous = np.concatenate([starts[:, None], position[:, :-1]], axis=1)
    length = np.linalg.norm(position - previous, axis=-1)
    trial, step = np.nonzero(distance <= length.max())
    wall_a = verts[trial]
    wall_b = np.roll(verts, -1, axis=1)[trial]
    return int(geometry.cross(previous[trial, step, None], position[trial, step, None],
                              wall_a, wall_b).sum())


@pytest.mark.parametrize("config", [
    ArenaConfig(mean_radius=0.33),
    ArenaConfig(mean_radius=1.0),
    ArenaConfig(mean_radius=0.33, radius_spread=0.9, angle_jitter=0.49),   # sharp corners
], ids=["small", "large", "spiky"])
def test_no_sample_ever_outside_its_arena(config, geometry):
    """Thousands of random arenas, every fine step checked, and every move between them."""
    rng = np.random.default_rng(20)
    verts = np.stack([random_vertices(rng, config) for _ in range(700)])
    motion = every_fine_step(400)
    starts, out = run(verts, motion, rng)
    position = out["position"]
    assert contains(verts, position).all()
    distance, _, _ = wall_distance(verts, position)
    assert distance.min() >= SENSORS.min_clearance
    assert crossings(verts, starts, position, distance, geometry) == 0
    assert out["contact"].sum() > 1000          # the walls were really tested


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1),
       mean_speed=st.floats(0.05, 0.4),
       speed_sd=st.floats(0.0, 0.2),
       turn_sd=st.floats(0.0, 4.0),
       n_vertices=st.integers(4, 16),
       spread=st.floats(0.0, 0.9),
       jitter=st.floats(0.0, 0.49))
def test_no_sample_outside_for_any_motion_statistics(seed, mean_speed, speed_sd, turn_sd,
                                                     n_vertices, spread, jitter):
    rng = np.random.default_rng(seed)
    config = ArenaConfig(n_vertices=n_vertices, mean_radius=0.33, radius_spread=spread,
                         angle_jitter=jitter)
    verts = np.stack([random_vertices(rng, config) for _ in range(40)])
    # the fastest fine step stays shorter than the touch range, as MotionConfig requires
    motion = every_fine_step(300, mean_speed=mean_speed, speed_sd=speed_sd, turn_sd=turn_sd,
                             max_speed=0.9 * SENSORS.touch_range / MotionConfig.fine_dt)
    _, out = run(verts, motion, rng)
    assert contains(verts, out["position"]).all()
    distance, _, _ = wall_distance(verts, out["position"])
    assert distance.min() >= SENSORS.min_clearance


def test_contacts_only_within_touch_range_and_then_the_agent_turns_away():
    rng = np.random.default_rng(21)
    verts = np.stack([random_vertices(rng, ArenaConfig(mean_radius=0.33))
                      for _ in range(500)])
    _, out = run(verts, every_fine_step(400), rng)
    touched = out["contact"]
    assert touched.sum() > 1000
    distance, _, normal = wall_distance(verts, out["position"])
    # the sensed contact is the true distance from where the agent is to the nearest wall
    assert (out["contact_distance"][touched] < SENSORS.touch_range).all()
    np.testing.assert_allclose(out["contact_distance"][touched], distance[touched],
                               rtol=0, atol=1e-12)
    assert (out["contact_distance"][~touched] == 0).all()
    assert (out["contact_angle"][~touched] == 0).all()
    # beta is the angle from the inward normal to the heading: the agent was heading into
    # the wall (|beta| > pi/2), except when a corner refused its step
    beta = out["contact_angle"][touched]
    assert (np.abs(beta) <= np.pi).all()
    assert np.mean(np.cos(beta) < 0) > 0.99
    # after the contact it heads away from (or along) the wall
    heading = out["heading"]
    away = np.cos(heading) * normal[..., 0] + np.sin(heading) * normal[..., 1]
    assert (away[touched] >= -1e-9).all()


def test_contacts_at_the_network_step_report_the_first_touch():
    rng = np.random.default_rng(22)
    verts = np.stack([random_vertices(rng, ArenaConfig(mean_radius=0.33))
                      for _ in range(300)])
    _, out = run(verts, MotionConfig(n_steps=200), rng)
    touched = out["contact"]
    assert touched.mean() > 0.05
    assert ((out["contact_distance"][touched] > 0)
            & (out["contact_distance"][touched] < SENSORS.touch_range)).all()
    assert (out["contact_distance"][~touched] == 0).all()


def test_kinematics_and_heading_range():
    rng = np.random.default_rng(23)
    verts = np.stack([random_vertices(rng, ArenaConfig(mean_radius=0.33))
                      for _ in range(200)])
    motion = MotionConfig(n_steps=300)
    starts, out = run(verts, motion, rng)
    heading = out["heading"]
    assert ((heading >= -np.pi) & (heading < np.pi)).all()
    # the displacement of each step telescopes to the trajectory
    np.testing.assert_allclose(starts[:, None] + np.cumsum(out["displacement"], axis=1),
                               out["position"], rtol=0, atol=1e-12)
    steps = np.linalg.norm(out["displacement"], axis=-1)
    assert steps.max() <= motion.max_speed * motion.network_dt + 1e-12


def test_straight_run_at_constant_speed_without_noise():
    """No speed or turning noise and no wall in reach: a straight line at mean speed."""
    motion = every_fine_step(400, speed_sd=0.0, turn_sd=0.0)
    verts = np.repeat(regular_polygon(10, 100.0).vertices[None], 3, axis=0)
    heading0 = np.array([0.3, -2.0, 3.0])
    _, out = run(verts, motion, np.random.default_rng(0), starts=np.zeros((3, 2)),
                 heading0=heading0)
    t = motion.fine_dt * np.arange(1, motion.n_steps + 1)
    expected = (motion.mean_speed * t[None, :, None]
                * np.stack([np.cos(heading0), np.sin(heading0)], axis=-1)[:, None])
    np.testing.assert_allclose(out["position"], expected, rtol=0, atol=1e-9)
    np.testing.assert_allclose(out["heading"], np.broadcast_to(heading0[:, None], t.shape[:0]
                                                               + (3, len(t))), atol=1e-12)
    assert not out["contact"].any()


def test_speed_and_turning_follow_their_ornstein_uhlenbeck_statistics():
    """Far from any wall, the sampled speed and angular velocity have the configured
    mean, stationary s.d. and correlation time (Euler-Maruyama AR(1):
    var = sd^2 / (1 - dt / (2 tau)))."""
    motion = every_fine_step(4000)
    n = 100
    verts = np.repeat(regular_polygon(10, 1000.0).vertices[None], n, axis=0)
    _, out = run(verts, motion, np.random.default_rng(24), starts=np.zeros((n, 2)))
    assert not out["contact"].any()
    dt = motion.fine_dt
    burn = int(5 * motion.speed_tau / dt)
    speed = np.linalg.norm(out["displacement"], axis=-1)[:, burn:] / dt
    turn = np.diff(np.unwrap(out["heading"], axis=1), axis=1)[:, burn:] / dt
    assert speed.mean() == pytest.approx(motion.mean_speed, rel=0.03)
    assert speed.std() == pytest.approx(
        motion.speed_sd / np.sqrt(1 - dt / (2 * motion.speed_tau)), rel=0.05)
    assert turn.mean() == pytest.approx(0.0, abs=0.05 * motion.turn_sd)
    assert turn.std() == pytest.approx(
        motion.turn_sd / np.sqrt(1 - dt / (2 * motion.turn_tau)), rel=0.05)
    for x, tau in ((speed, motion.speed_tau), (turn, motion.turn_tau)):
        lag = int(round(tau / dt))
        x = x - x.mean()
        rho = np.mean(x[:, lag:] * x[:, :-lag]) / x.var()
        assert rho == pytest.approx(np.exp(-1), abs=0.05)


def test_trials_do_not_depend_on_batching_or_threads():
    rng = np.random.default_rng(25)
    n = 16
    motion = MotionConfig(n_steps=100)
    verts = np.stack([random_vertices(rng, ArenaConfig(mean_radius=0.33)) for _ in range(n)])
    starts = clear_starts(verts, rng, SENSORS.touch_range)
    heading0 = rng.uniform(-np.pi, np.pi, n)
    noise = rng.standard_normal((2, n, motion.n_steps * motion.substeps))
    whole = simulate_motion(verts, starts, heading0, noise[0], noise[1], motion, SENSORS)
    half = [simulate_motion(verts[s], starts[s], heading0[s], noise[0, s], noise[1, s],
                            motion, SENSORS) for s in (slice(0, 5), slice(5, n))]
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        single = simulate_motion(verts, starts, heading0, noise[0], noise[1], motion, SENSORS)
    finally:
        numba.set_num_threads(threads)
    for key, value in whole.items():
        np.testing.assert_array_equal(value, np.concatenate([h[key] for h in half]))
        np.testing.assert_array_equal(value, single[key])


def test_noise_of_the_wrong_shape_raises():
    verts = regular_polygon(10, 1.0).vertices[None]
    motion = MotionConfig(n_steps=10)
    good = np.zeros((1, 10 * motion.substeps))
    with pytest.raises(ValueError, match=r"`speed_noise`.*\(1, 79\)"):
        simulate_motion(verts, np.zeros((1, 2)), np.zeros(1), good[:, :-1], good, motion,
                        SENSORS)
    with pytest.raises(ValueError, match=r"`turn_noise`.*\(2, 80\)"):
        simulate_motion(verts, np.zeros((1, 2)), np.zeros(1), good, np.zeros((2, 80)), motion,
                        SENSORS)


@pytest.mark.parametrize("make, name, value", [
    (lambda: MotionConfig(fine_dt=0.0), "fine_dt", "0.0"),
    (lambda: MotionConfig(fine_dt=-0.05), "fine_dt", "-0.05"),
    (lambda: MotionConfig(network_dt=0.0), "network_dt", "0.0"),
    (lambda: MotionConfig(network_dt=0.42), "network_dt", "0.42"),
    (lambda: MotionConfig(n_steps=0), "n_steps", "0"),
    (lambda: MotionConfig(n_steps=-5), "n_steps", "-5"),
    (lambda: MotionConfig(mean_speed=-0.1), "mean_speed", "-0.1"),
    (lambda: MotionConfig(speed_tau=0.0), "speed_tau", "0.0"),
    (lambda: MotionConfig(turn_sd=-1.0), "turn_sd", "-1.0"),
    (lambda: MotionConfig(min_speed=0.6), "min_speed", "0.6"),
    (lambda: SensorConfig(touch_range=0.0), "touch_range", "0.0"),
    (lambda: SensorConfig(min_clearance=0.06), "min_clearance", "0.06"),
])
def test_bad_motion_parameters_raise_naming_parameter_and_value(make, name, value):
    with pytest.raises(ValueError, match=rf"`{name}`.*{value}"):
        make()
