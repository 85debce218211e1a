r"""Oracular particle filter (PF): the Bayes-optimal position estimate given the arena.

The filter tracks the posterior :math:`p(x_t, \eta_t \mid \text{inputs}_{1..t},
\text{arena})` of the end-of-step position and heading drift with ``N`` weighted
particles (bootstrap filter, Gordon, Salmond & Smith 1993); in the compass world the
drift is 0 and never moves. Each network step:

1. **Motion.** Every particle's drift takes the world's Wiener step,
   :math:`\eta_i \leftarrow \eta_i + \sigma_\eta\sqrt{\delta t}\,z`, and the particle
   moves by :math:`(1 + e_s)\,R(e_r - \eta_i)\,D^{obs}` (the displacement was sensed in
   the frame turned by the drift) with
   :math:`e_s \sim N(0, \sigma_s^2)`, :math:`e_r \sim N(0, \sigma_r^2)` from the world's
   :class:`~hippo_probe.world.config.NoiseModel`: to first order the true step is
   :math:`(1 - e_s)R(-e_r)D^{obs}`, which has that distribution. Measured on 400 trials
   without walls, the true steps' errors about this proposal have 0.95 times its
   variance per step and 0.95-1.04 times it summed over 5-500 steps (uncorrelated). The
   exact inversion :math:`R(-e_r)D^{obs}/(1 + e_s)` overstates it by 20-25% (a division
   inflates the spread), and a per-step posterior with a prior on the step length
   understates it three-fold over 100 steps (the speed persists across steps, so its
   errors add up coherently); both left the filter miscalibrated.
2. **Weight.** A particle outside the arena, or nearer a wall than the simulator ever
   goes (``min_clearance``), gets weight 0. Otherwise its weight is multiplied by the
   likelihood of what was sensed (:mod:`~hippo_probe.baselines.contact`): for a contact,
   the sum over walls of the angle likelihood times the likelihood of the sensed
   distance given the particle's start and end distances to that wall, plus an outlier
   floor (with ``ContactModelConfig.outlier_near_walls``, only for particles whose path
   could have reached a wall); for no contact, the probability that it would not have
   touched: ``0`` when it ends within ``touch_range`` of its nearest wall heading into
   it, softened by the heading noise, and the same at the step's midpoint. If every
   particle contradicts the step's observation (weights sum to 0) the observation is
   skipped for the particles inside the arena, and counted in ``attrs["n_skipped"]``.
3. **Estimate.** Posterior mean and covariance (xx, yy, xy) from the weighted particles.
4. **Resampling.** Systematic resampling when the effective sample size
   :math:`1/\sum_i w_i^2` drops below ``resample_threshold * N``. With
   ``ParticleFilterConfig.contact_proposals`` = m > 1, at a contact step every particle
   splits into m children before step 1 (each 1/m of its weight, moving independently),
   and step 4 always resamples back to ``N``: m times the proposals where the
   likelihood is sharpest, at about m times the cost of those ~5% of steps.
   With an unknown start (``ParticleFilterConfig.unknown_start_regularization`` = 0.3)
   each resampling is followed by a Gaussian kernel move of covariance
   :math:`h^2 \Sigma`, :math:`\Sigma` the particles' covariance (a regularized filter,
   Musso, Oudjane & Le Gland 2001); with a known start, none (``regularization`` = 0).

Approximations of the contact process (the simulator runs at 8 fine steps per network
step; the filter sees only the network step and its particles' start and end):

* a sensed contact happened at *some* fine step inside the step, while the particle's
  positions are those at the step's start and end: the path between them is taken to be
  a "V" reflected off the touched wall, whose apex is the contact; the unknown path
  length (from the sensed displacements) and angle widen the distance likelihood, and an
  outlier floor covers double contacts in corners and large turns after the reflection;
* the touched wall is summed over (any wall whose normal matches the sensed angle), not
  required to be the nearest wall at the contact;
* absence of contact is checked at the step's end (exactly where the simulator's last
  fine-step check happens) and at the step's midpoint on the straight chord, not at the
  other fine steps; the heading there is the sensed end heading turned back by the
  sensed turn (noise ``head_direction_sd``);
* the heading inputs serve the contact angle and the no-contact test only, not the
  direction of the displacement; the speed's persistence across steps is not used;
* every heading-dependent term uses the particle's own heading, the sensed heading minus
  its drift :math:`h - \eta_i` (so the contact-angle likelihood is evaluated per particle).

With these, the converged filter is calibrated (:mod:`~hippo_probe.baselines.calibration`,
``analyses/pf_calibration.py``; ranks of the truth 20 s apart on validation trials,
darkness world): the ranks of the true position and drift among the particles are
uniform within sampling error (per-time KS) on 300 trials per task at the defaults of the
generalized and specialized tasks (the 90% region holds 0.884-0.903 of the truths), and
on 1,000 localization trials at 20,000 particles (0.895-0.902). At the localization
task's default 2,000 particles, plain resampling leaves the position posterior too
narrow (its 90% region holds 0.870-0.874): Monte Carlo error, which shrinks with the
particles (0.889 at 5,000) and sits 2-20 s after contacts, though not made at the
contact step itself (splitting the particles there,
``ParticleFilterConfig.contact_proposals``, does not remove it). The
localization filter's kernel after resampling (step 4) removes that over-confidence at
2,000 particles (0.898 in the 90% region) and brings its error to the 20,000-particle
filter's. In an earlier contact model the outlier floor went to every particle, deep in
the arena too, which made the converged filter under-confident at a localization
trial's first contact (``ContactModelConfig.outlier_near_walls``).

Implementation: one numba kernel per trial (``nogil``), trials spread over a thread pool.
Particles are stored as separate contiguous ``x``/``y`` arrays, and the wall-distance
kernel loops over walls outside and particles inside with branch-free arithmetic, which
compiles to SIMD code (~1 ns per particle and wall, ten times the particle-outer loop).
The motion step draws its random numbers particle by particle (the stream's order) and
does its arithmetic, the rotation's cosine and sine above all, in separate branch-free
loops, which vectorize as well: 9% more particle-steps per second than one loop doing
both (``benchmarks/bench_particle_filter.py``), with the same numbers bit for bit.
Each trial draws its random numbers from ``SeedSequence([seed, tag, trial_index])``:
results do not depend on batching or thread count.

References
----------
Musso, C., Oudjane, N., & Le Gland, F. (2001). Improving regularised particle filters.
In Sequential Monte Carlo Methods in Practice (Doucet, de Freitas & Gordon, eds.),
247-271. Springer.
Gordon, N. J., Salmond, D. J., & Smith, A. F. M. (1993). Novel approach to
nonlinear/non-Gaussian Bayesian state estimation. IEE Proc. F 140:107-113.
Doucet, A., & Johansen, A. M. (2009). A tutorial on particle filtering and smoothing:
fifteen years later. Handbook of Nonlinear Filtering 12:656-704.
Cheung, A., Ball, D., Milford, M., Wyeth, G., & Wiles, J. (2012). PLoS Comput Biol
8:e1002651.
Kanitscheider, I., & Fiete, I. (2017). Training recurrent networks to generate hypotheses
about how the brain solves hard navigation problems. NIPS 30 (the PF baselines).
"""

from __future__ import annotations

import math
from collections import namedtuple
from concurrent.futures import ThreadPoolExecutor

import numba
import numpy as np

from .._docs import fill_doc
from .._validators import check_positive
from ..tasks import TaskConfig
from ._common import BaselineResult, provenance, resolve_start, resolve_task, start_prior_samples
from .config import STREAM_TAGS, BaselineConfig
from .contact import ContactModel, Observations, towards, wall_table, wall_terms

# The kernel's arguments, grouped and read by name (a swapped argument cannot pass).
#: One trial's initial particles: positions, their start, heading drift, arena hypothesis.
Particles = namedtuple("Particles", "x y sx sy eta arena")
#: One trial's self-motion and contact observations, per step.
TrialObservations = namedtuple(
    "TrialObservations", "displacement heading turn contact distance angle path_length")
#: The filter's model of the world and its own settings.
FilterModel = namedtuple(
    "FilterModel", "n_checks speed_sd rotation_sd drift_step_sd resample_threshold "
                   "contact_args heading_sd touch_range min_clearance outlier_p "
                   "outlier_density outlier_reach floor proposals regularization relative "
                   "class_output")
#: Where one trial's estimates and particle snapshots are written.
TrialOutputs = namedtuple(
    "TrialOutputs", "snapshot_of_step estimate mean cov drift classes snap_xy snap_w "
                    "snap_eta snap_arena")


@fill_doc
def particle_filter(batch, n_particles: int | None = None, *, start: str | None = None,
                    oriented: bool = True, keep=(), threads: int | None = None,
                    config: TaskConfig | None = None,
                    baseline: BaselineConfig | None = None) -> BaselineResult:
    """Oracular particle filter: the arena of each trial is known; see the module docstring.

    Parameters
    ----------
    %(batch)s
    n_particles : int, optional
        Particles per trial (default ``ParticleFilterConfig.n_particles`` = 1,000 with a
        known start, ``unknown_start_particles`` = 2,000 with an unknown one).
    start : {"known", "unknown"}, optional
        Unknown: particles start uniform in the arena (at least the touch range from its
        walls, as the tasks draw starts). Default: unknown for localization, known
        otherwise.
    oriented : bool
        Whether the heading drift is known to start at 0 (the world's trials: the rat is
        oriented when a trial begins). False starts the drift hypotheses uniform on
        [-pi, pi): the start heading is unknown.
    keep : sequence of int
        Steps whose particles, weights and drifts to return (``result.particles``).
    %(threads)s
    %(baseline_config)s

    Returns
    -------
    BaselineResult
        ``estimate`` (T, B, 2) in the target frame, ``mean`` (T, B, 2) and ``cov``
        (T, B, 3) of the position in the arena frame, ``drift_mean`` and ``drift_sd``
        (T, B) of the heading drift; ``attrs`` count resamplings and skipped
        observations.

    Examples
    --------
    >>> from hippo_probe.tasks import make_trials
    >>> batch = make_trials("localization", n_trials=2, split="test")
    >>> res = particle_filter(batch, n_particles=200)
    >>> res.estimate.shape, res.cov.shape
    ((500, 2, 2), (500, 2, 3))
    """
    config = resolve_task(batch, config)
    baseline = baseline or BaselineConfig()
    start = resolve_start(start, config)
    pf = baseline.particle_filter
    unknown = start == "unknown"
    if n_particles is None:
        n_particles = pf.unknown_start_particles if unknown else pf.n_particles
    n_particles = check_positive("n_particles", n_particles, integer=True)
    # the kernel's covariance is linear in the drift: meaningless once the drift
    # hypotheses span the circle (start heading unknown)
    regularization = ((pf.unknown_start_regularization if unknown else pf.regularization)
                      if oriented else 0.0)
    tables = wall_table(batch.arena_vertices)[:, None]           # (B, 1, V, 8)
    run = run_filter(batch, tables, np.arange(len(batch)), n_particles, start, config,
                     baseline, "particle_filter", oriented=oriented, keep=keep,
                     threads=threads, regularization=regularization)
    return BaselineResult(
        "pf", run["estimate"], mean=run["mean"], cov=run["cov"],
        drift_mean=run["drift_mean"], drift_sd=run["drift_sd"],
        particles=run["particles"], particle_weights=run["weights"],
        particle_drifts=run["drifts"],
        attrs=provenance("pf", batch, n_particles=n_particles, start=start,
                         oriented=bool(oriented), regularization=regularization,
                         **run["diagnostics"]))


def run_filter(batch, tables, table_of_trial, n_particles, start, config, baseline, stream,
               *, oriented=True, keep=(), threads=None, class_output=False,
               regularization=None):
    """Run the particle kernel on every trial of ``batch``.

    ``tables`` (n_tables, A, V, 8) holds wall tables of ``A`` arena hypotheses; trial ``b``
    uses ``tables[table_of_trial[b]]`` and its particles start spread evenly over the
    ``A`` hypotheses (particle ``i`` in arena ``i * A // N``). Particles carry a heading
    drift hypothesis, 0 at the start if ``oriented`` (else uniform on [-pi, pi)),
    diffusing as the world's drift does; ``regularization`` is the bandwidth of the kernel
    after resampling (default ``ParticleFilterConfig.regularization``). Returns a dict of
    time-major outputs.
    """
    n_trials, n_steps = len(batch), batch.n_steps
    n_arenas = tables.shape[1]
    if n_particles < n_arenas:
        raise ValueError(f"`n_particles` must be >= the number of arena hypotheses "
                         f"({n_arenas}); got {n_particles}")
    keep = np.unique(np.asarray(keep, dtype=np.int64))
    if keep.size and (keep.min() < 0 or keep.max() >= n_steps):
        raise ValueError(f"`keep` must hold steps in [0, {n_steps - 1}]; got {keep.tolist()}")
    threads = check_positive("threads", numba.get_num_threads() if threads is None else threads,
                             integer=True)
    pf = baseline.particle_filter
    regularization = pf.regularization if regularization is None else regularization
    model = ContactModel.from_config(config.world, baseline.contact)
    noise = config.world.noise
    drift_step_sd = noise.heading_drift * math.sqrt(batch.dt)
    obs = Observations.from_batch(batch)
    relative = config.target == "start_relative"
    snapshot_of_step = np.full(n_steps, -1, dtype=np.int64)
    snapshot_of_step[keep] = np.arange(keep.size)

    estimate = np.empty((n_trials, n_steps, 2))
    mean = np.empty((n_trials, n_steps, 2))
    cov = np.empty((n_trials, n_steps, 3))
    drift = np.empty((n_trials, n_steps, 2))                     # mean, s.d.
    classes = np.empty((n_trials, n_steps, n_arenas if class_output else 0), np.float32)
    snap_xy = np.empty((n_trials, keep.size, n_particles, 2))
    snap_w = np.empty((n_trials, keep.size, n_particles))
    snap_eta = np.empty((n_trials, keep.size, n_particles))
    snap_arena = np.empty((n_trials, keep.size, n_particles), np.int64)
    counts = np.zeros((n_trials, 2), np.int64)
    arena = (np.arange(n_particles) * n_arenas // n_particles).astype(np.int64)
    clearance = config.world.sensors.touch_range
    floor = int(pf.arena_floor * n_particles / n_arenas) if n_arenas > 1 else 0

    kernel_model = FilterModel(
        n_checks=pf.intermediate_checks, speed_sd=noise.speed_sd,
        rotation_sd=noise.rotation_sd, drift_step_sd=drift_step_sd,
        resample_threshold=pf.resample_threshold, contact_args=model.kernel_args(),
        heading_sd=model.heading_sd, touch_range=model.touch_range,
        min_clearance=model.min_clearance, outlier_p=model.outlier_probability,
        outlier_density=model.outlier_density, outlier_reach=model.outlier_reach,
        floor=floor, proposals=pf.contact_proposals, regularization=float(regularization),
        relative=relative, class_output=class_output)

    def one(b):
        rng = np.random.default_rng(np.random.SeedSequence(
            [int(batch.seed), STREAM_TAGS[stream], int(batch.trial_index[b])]))
        if start == "known":
            x0 = np.broadcast_to(np.asarray(batch.start[b], np.float64), (n_particles, 2))
        else:
            x0 = start_prior_samples(batch.arena_vertices[b], rng, n_particles, clearance)
        x, y = np.ascontiguousarray(x0[:, 0]), np.ascontiguousarray(x0[:, 1])
        eta = np.zeros(n_particles) if oriented else rng.uniform(-np.pi, np.pi, n_particles)
        counts[b] = _filter_trial(
            rng, Particles(x=x, y=y, sx=x.copy(), sy=y.copy(), eta=eta, arena=arena.copy()),
            tables[table_of_trial[b]],
            TrialObservations(displacement=obs.displacement[b], heading=obs.heading[b],
                              turn=obs.turn[b], contact=obs.contact[b],
                              distance=obs.distance[b], angle=obs.angle[b],
                              path_length=obs.path_length[b]),
            kernel_model,
            TrialOutputs(snapshot_of_step=snapshot_of_step, estimate=estimate[b],
                         mean=mean[b], cov=cov[b], drift=drift[b], classes=classes[b],
                         snap_xy=snap_xy[b], snap_w=snap_w[b], snap_eta=snap_eta[b],
                         snap_arena=snap_arena[b]))

    if threads == 1 or n_trials == 1:
        for b in range(n_trials):
            one(b)
    else:
        with ThreadPoolExecutor(min(threads, n_trials)) as pool:
            list(pool.map(one, range(n_trials)))

    def time_major(a):
        return np.ascontiguousarray(np.swapaxes(a, 0, 1))

    return {
        "estimate": time_major(estimate), "mean": time_major(mean), "cov": time_major(cov),
        "drift_mean": time_major(drift[..., 0]), "drift_sd": time_major(drift[..., 1]),
        "class_probability": time_major(classes) if class_output else None,
        "particles": time_major(snap_xy) if keep.size else None,
        "weights": time_major(snap_w) if keep.size else None,
        "drifts": time_major(snap_eta) if keep.size else None,
        "arenas": time_major(snap_arena) if keep.size else None,
        "diagnostics": {"mean_resamplings": float(counts[:, 1].mean()),
                        "n_skipped": int(counts[:, 0].sum()),
                        "kept_steps": keep.tolist()},
    }


@numba.njit(cache=True, nogil=True)
def _cos_sin(r, c, s):
    """``c, s = cos(r), sin(r)`` of the first ``c.size`` angles, which are mostly small:
    Taylor series to 3e-7 below 1 rad (the rotation noise is 0.18 rad), the library
    functions beyond.

    The series go over every angle in a loop without branches, which LLVM turns into
    vector code (its eight divisions per angle are most of the cost: a vector division
    does four or eight angles at once), each angle's operations those of the scalar
    series; the few angles beyond 1 rad are redone after with the C library's functions
    (numba's SVML, used only where Intel's ``icc_rt`` is installed, could vectorize those
    calls too and round them differently in the last bit).
    """
    for i in range(c.size):
        r2 = r[i] * r[i]
        c[i] = 1.0 - r2 / 2.0 * (1.0 - r2 / 12.0 * (1.0 - r2 / 30.0 * (1.0 - r2 / 56.0)))
        s[i] = r[i] * (1.0 - r2 / 6.0 * (1.0 - r2 / 20.0 * (1.0 - r2 / 42.0
                                                            * (1.0 - r2 / 72.0))))
    for i in range(c.size):
        if abs(r[i]) >= 1.0:
            c[i], s[i] = math.cos(r[i]), math.sin(r[i])


@numba.njit(cache=True, nogil=True)
def _nearest_walls(walls, x, y, best, nearest, crossings):
    """Squared distance to the nearest wall, its index, and the number of walls crossed by
    the ray towards +x (odd: inside) of particles ``x, y`` in one arena (``walls (V, 8)``).

    Walls outside, particles inside, branch-free float arithmetic over whole (sliced)
    arrays: indices provably in ``[0, size)`` let LLVM drop numba's negative-index
    handling and compile the inner loop to SIMD code (about 1 ns per particle and wall,
    ten times the scalar loop)."""
    best[:] = np.inf
    nearest[:] = 0.0
    crossings[:] = 0.0
    for k in range(walls.shape[0]):
        ax, ay, ex, ey, inv_length2 = (walls[k, 0], walls[k, 1], walls[k, 2], walls[k, 3],
                                       walls[k, 4])
        wall = float(k)
        for i in range(x.size):
            rx = x[i] - ax
            ry = y[i] - ay
            u = min(max((rx * ex + ry * ey) * inv_length2, 0.0), 1.0)
            qx = rx - u * ex
            qy = ry - u * ey
            d2 = qx * qx + qy * qy
            previous = best[i]
            nearest[i] = wall if d2 < previous else nearest[i]
            best[i] = min(d2, previous)
            straddles = (ry < 0.0) != (ry < ey)
            left_of = (rx * ey < ry * ex) == (ey > 0.0)
            crossings[i] += 1.0 if (straddles and left_of) else 0.0


@numba.njit(cache=True, nogil=True)
def _filter_trial(rng, particles, walls, obs, model, outputs):
    """One trial of the particle filter (module docstring, steps 1-4). ``particles``
    (:data:`Particles`: ``x, y``, their start ``sx, sy``, heading drift ``eta`` and arena
    hypothesis ``arena``, sorted by arena) are the initial ones, ``obs`` the trial's
    :data:`TrialObservations`, ``model`` the :data:`FilterModel`; the estimates go into
    ``outputs`` (:data:`TrialOutputs`). Returns (number of skipped observations, number of
    resamplings).

    At a contact step with ``proposals`` = m > 1, each particle first splits into m
    children of weight w/m that move independently; the step's estimate uses all of them
    and resampling returns to ``n`` particles (snapshots are then taken after it)."""
    x, y, sx, sy, eta, arena = (particles.x, particles.y, particles.sx, particles.sy,
                                particles.eta, particles.arena)
    disp, heading, turn, contact = obs.displacement, obs.heading, obs.turn, obs.contact
    distance, angle, path_length = obs.distance, obs.angle, obs.path_length
    n_checks, speed_sd, rotation_sd = model.n_checks, model.speed_sd, model.rotation_sd
    drift_step_sd, resample_threshold = model.drift_step_sd, model.resample_threshold
    contact_args, heading_sd, touch_range = (model.contact_args, model.heading_sd,
                                             model.touch_range)
    min_clearance, outlier_p = model.min_clearance, model.outlier_p
    outlier_density, outlier_reach = model.outlier_density, model.outlier_reach
    floor, proposals, regularization = model.floor, model.proposals, model.regularization
    relative, class_output = model.relative, model.class_output
    snapshot_of_step = outputs.snapshot_of_step
    out_estimate, out_mean, out_cov = outputs.estimate, outputs.mean, outputs.cov
    out_drift, out_class = outputs.drift, outputs.classes
    snap_xy, snap_w = outputs.snap_xy, outputs.snap_w
    snap_eta, snap_arena = outputs.snap_eta, outputs.snap_arena
    n = x.size
    cap = n * proposals
    n_arenas = walls.shape[0]
    x, y, sx, sy, eta, arena = (_grown(x, cap), _grown(y, cap), _grown(sx, cap),
                                _grown(sy, cap), _grown(eta, cap), _grown(arena, cap))
    w = np.full(cap, 1.0 / n)
    lik = np.empty(cap)
    best = np.empty(cap)
    nearest = np.empty(cap)
    crossings = np.empty(cap)
    xp, yp = np.empty(cap), np.empty(cap)
    xm, ym, mid_best, mid_nearest, mid_crossings = (np.empty(cap), np.empty(cap),
                                                   np.empty(cap), np.empty(cap),
                                                   np.empty(cap))
    x2, y2, sx2, sy2, eta2 = (np.empty(cap), np.empty(cap), np.empty(cap), np.empty(cap),
                              np.empty(cap))
    arena2 = np.empty(cap, dtype=arena.dtype)
    w2 = np.empty(cap)
    gain, rotation, cosine, sine, wall_distance = (np.empty(cap), np.empty(cap),
                                                   np.empty(cap), np.empty(cap),
                                                   np.empty(cap))
    near = np.empty(cap, dtype=np.int64)
    alloc = np.empty(n_arenas, dtype=np.int64)
    mass = np.empty(n_arenas)
    block = np.zeros(n_arenas + 1, dtype=np.int64)
    n_skipped = 0
    n_resampled = 0
    cur = n                  # particles now: n, or n * proposals in a split step
    near_walls_only = outlier_reach < math.inf
    for t in range(disp.shape[0]):
        touched = contact[t]
        split = touched and proposals > 1
        if split:
            # m children per particle, kept contiguous (so still sorted by arena); from
            # the last particle down, so no particle is overwritten before it is copied
            for i in range(n - 1, -1, -1):
                for c in range(proposals - 1, -1, -1):
                    j = i * proposals + c
                    x[j], y[j], sx[j], sy[j] = x[i], y[i], sx[i], sy[i]
                    eta[j], arena[j], w[j] = eta[i], arena[i], w[i] / proposals
            cur = cap
        # 1. motion: the drift diffuses, then D = (1 + e_s) R(e_r - eta) D_obs, the
        # first-order inverse of the sensor (the displacement was sensed in the frame
        # turned by the drift)
        # (the draws one particle after another, the order in which the random stream is
        # read; the arithmetic in loops of their own, which vectorize)
        dox, doy = disp[t, 0], disp[t, 1]
        for i in range(cur):
            if drift_step_sd > 0.0:
                eta[i] += drift_step_sd * rng.standard_normal()
            gain[i] = max(1.0 + speed_sd * rng.standard_normal(), 0.0)
            rotation[i] = rotation_sd * rng.standard_normal() - eta[i]
        _cos_sin(rotation[:cur], cosine[:cur], sine[:cur])
        for i in range(cur):
            c, s = gain[i] * cosine[i], gain[i] * sine[i]
            xp[i], yp[i] = x[i], y[i]
            x[i] += c * dox - s * doy
            y[i] += s * dox + c * doy
        # 2. weights, one arena block at a time (particles are sorted by arena); each
        # particle reads the heading-dependent terms with its own heading, sensed - eta
        block[1:] = 0
        for i in range(cur):
            block[arena[i] + 1] += 1
        for a in range(n_arenas):
            block[a + 1] += block[a]
        for a in range(n_arenas):
            lo, hi = block[a], block[a + 1]
            if lo == hi:
                continue
            _nearest_walls(walls[a], x[lo:hi], y[lo:hi], best[lo:hi], nearest[lo:hi],
                           crossings[lo:hi])
            if touched:
                _contact_likelihood(walls[a], heading[t], angle[t], path_length[t],
                                    contact_args, distance[t], eta[lo:hi], xp[lo:hi],
                                    yp[lo:hi], x[lo:hi], y[lo:hi], lik[lo:hi])
                if near_walls_only:
                    # the start's nearest wall too, for the outlier floor's reach (the
                    # midpoint buffers are free: no-contact checks run on other steps)
                    _nearest_walls(walls[a], xp[lo:hi], yp[lo:hi], mid_best[lo:hi],
                                   mid_nearest[lo:hi], mid_crossings[lo:hi])
        for i in range(cur):            # apart from the branches below: vectorized
            wall_distance[i] = math.sqrt(best[i])
        for i in range(cur):
            d = wall_distance[i]
            if int(crossings[i]) % 2 == 0 or d < min_clearance:
                lik[i] = 0.0
            elif touched:
                # an unexplained contact still needs a wall within reach of the path
                reachable = (not near_walls_only
                             or d + math.sqrt(mid_best[i]) <= outlier_reach)
                lik[i] = (1.0 - outlier_p) * lik[i] + (
                    outlier_p * outlier_density if reachable else 0.0)
            elif d < touch_range:
                lik[i] = 1.0 - towards(walls[arena[i], int(nearest[i]), 7],
                                       heading[t] - eta[i], heading_sd)
            else:
                lik[i] = 1.0
        if not touched:
            # no contact at the fine steps inside the step either: particles on the chord
            # from start to end, headings turning by the sensed change
            for j in range(1, n_checks + 1):
                _intermediate_check(j / (n_checks + 1.0), heading[t], turn[t], walls, block,
                                    xp[:cur], yp[:cur], x[:cur], y[:cur], eta[:cur],
                                    arena[:cur], wall_distance[:cur], touch_range,
                                    heading_sd, lik[:cur], near, xm, ym, mid_best,
                                    mid_nearest, mid_crossings)
        total = 0.0
        for i in range(cur):
            total += w[i] * lik[i]
        if total > 0.0:
            for i in range(cur):
                w[i] *= lik[i] / total
        else:
            # the observation contradicts every particle: skip it for those still inside
            n_skipped += 1
            for i in range(cur):
                ok = int(crossings[i]) % 2 == 1 and best[i] >= min_clearance * min_clearance
                lik[i] = 1.0 if ok else 0.0
                total += w[i] * lik[i]
            if total > 0.0:
                for i in range(cur):
                    w[i] *= lik[i] / total
            else:                                  # every particle left: undo the move
                for i in range(cur):
                    x[i], y[i] = xp[i], yp[i]
        # 3. estimates
        mx = my = tx = ty = me = sum_w2 = 0.0
        mass[:] = 0.0
        for i in range(cur):
            mx += w[i] * x[i]
            my += w[i] * y[i]
            me += w[i] * eta[i]
            tx += w[i] * (x[i] - sx[i])
            ty += w[i] * (y[i] - sy[i])
            sum_w2 += w[i] * w[i]
            mass[arena[i]] += w[i]
        cxx = cyy = cxy = cee = 0.0
        for i in range(cur):
            dx, dy, de = x[i] - mx, y[i] - my, eta[i] - me
            cxx += w[i] * dx * dx
            cyy += w[i] * dy * dy
            cxy += w[i] * dx * dy
            cee += w[i] * de * de
        out_mean[t, 0], out_mean[t, 1] = mx, my
        out_drift[t, 0], out_drift[t, 1] = me, math.sqrt(cee)
        out_estimate[t, 0], out_estimate[t, 1] = (tx, ty) if relative else (mx, my)
        out_cov[t, 0], out_cov[t, 1], out_cov[t, 2] = cxx, cyy, cxy
        if class_output:
            for a in range(n_arenas):
                out_class[t, a] = mass[a]
        if not split:
            _snapshot(snapshot_of_step[t], x, y, w, eta, arena, snap_xy, snap_w, snap_eta,
                      snap_arena)
        # 4. resampling, arena by arena (keeps the particles sorted by arena); a split
        # step always returns to n particles
        resampled = split or 1.0 / sum_w2 < resample_threshold * cur
        if resampled:
            n_resampled += 1
            _allocate(mass, n, floor, rng.random(), alloc)
            out = 0
            for a in range(n_arenas):
                k = alloc[a]
                if k == 0:
                    continue
                lo, hi = block[a], block[a + 1]
                u0 = rng.random() / k
                cum = w[lo] / mass[a]
                j = lo
                for i in range(k):                 # systematic within the arena
                    target = u0 + i / k
                    while target > cum and j < hi - 1:
                        j += 1
                        cum += w[j] / mass[a]
                    x2[out], y2[out], sx2[out], sy2[out] = x[j], y[j], sx[j], sy[j]
                    eta2[out] = eta[j]
                    arena2[out] = a
                    w2[out] = mass[a] / k
                    out += 1
            x, x2 = x2, x
            y, y2 = y2, y
            sx, sx2 = sx2, sx
            sy, sy2 = sy2, sy
            eta, eta2 = eta2, eta
            arena, arena2 = arena2, arena
            w, w2 = w2, w
            cur = n
        if split:
            _snapshot(snapshot_of_step[t], x, y, w, eta, arena, snap_xy, snap_w, snap_eta,
                      snap_arena)
        # the kernel after resampling, arena by arena, once the step's snapshot is taken
        # (it shows the cloud the step's estimates came from); xp, yp, w2 and the
        # wall-distance buffers are free until the next step rewrites them
        if resampled and regularization > 0.0:
            lo = 0
            for a in range(n_arenas):
                hi = lo + alloc[a]
                if hi - lo > 1:
                    _regularize(rng, x[lo:hi], y[lo:hi], eta[lo:hi], regularization,
                                walls[a], min_clearance, xp[lo:hi], yp[lo:hi], w2[lo:hi],
                                best[lo:hi], nearest[lo:hi], crossings[lo:hi])
                lo = hi
    return n_skipped, n_resampled


@numba.njit(cache=True, nogil=True)
def _intermediate_check(f, heading, turn, walls, block, xs, ys, xe, ye, eta, arena,
                        end_distance, touch_range, heading_sd, lik, near, xm, ym, best,
                        nearest, crossings):
    """No contact at fraction ``f`` of the step: the likelihood ``lik`` of each particle
    moving from ``(xs, ys)`` to ``(xe, ye)`` whose point there on the chord is within the
    touch range of a wall is multiplied by the probability of not heading into that wall
    (the heading then ``heading - (1 - f) turn``, less the particle's drift).

    ``walls (A, V, 8)`` are the arenas' wall tables, ``block (A + 1,)`` the bounds of
    each arena's particles (sorted by arena) and ``end_distance`` each particle's distance
    from ``(xe, ye)`` to the nearest wall of its arena. Only particles that could be within
    the touch range are looked at: a point ``g`` from the chord's end is at least
    ``end_distance - g`` from every wall, so a particle with ``end_distance - g`` beyond
    the touch range (by a nanometre, for rounding; enough for coordinates up to
    kilometres) keeps the likelihood the full check would leave it. The others are
    gathered, arena by arena, into ``near, xm, ym``; ``best, nearest, crossings`` are
    scratch space for their walls.
    """
    back = heading - (1.0 - f) * turn
    reach = touch_range + 1e-9
    m = 0
    for a in range(block.size - 1):
        first = m
        for i in range(block[a], block[a + 1]):
            dx, dy = xe[i] - xs[i], ye[i] - ys[i]
            if end_distance[i] - (1.0 - f) * math.sqrt(dx * dx + dy * dy) > reach:
                continue
            near[m] = i
            xm[m] = xs[i] + f * dx
            ym[m] = ys[i] + f * dy
            m += 1
        if m > first:
            _nearest_walls(walls[a], xm[first:m], ym[first:m], best[first:m],
                           nearest[first:m], crossings[first:m])
    for q in range(m):
        if best[q] < touch_range * touch_range:
            i = near[q]
            lik[i] *= 1.0 - towards(walls[arena[i], int(nearest[q]), 7], back - eta[i],
                                    heading_sd)


@numba.njit(cache=True, nogil=True)
def _regularize(rng, x, y, eta, h, walls, min_clearance, x_old, y_old, eta_old, best,
                nearest, crossings):
    r"""Kernel jitter after resampling (regularized particle filter, Musso, Oudjane & Le
    Gland 2001) of one arena's equally weighted particles: each moves by
    :math:`h L z`, :math:`z \sim N(0, I_3)`, with :math:`L L^T = \Sigma` the particles'
    covariance of (x, y, drift), i.e. a Gaussian kernel of covariance :math:`h^2 \Sigma`; a
    move that leaves the arena (or comes nearer a wall than ``min_clearance``) is undone.
    The other arrays are scratch space."""
    n = x.size
    m0 = m1 = m2 = 0.0
    for i in range(n):
        m0 += x[i]
        m1 += y[i]
        m2 += eta[i]
    m0, m1, m2 = m0 / n, m1 / n, m2 / n
    c00 = c11 = c22 = c01 = c02 = c12 = 0.0
    for i in range(n):
        d0, d1, d2 = x[i] - m0, y[i] - m1, eta[i] - m2
        c00 += d0 * d0
        c11 += d1 * d1
        c22 += d2 * d2
        c01 += d0 * d1
        c02 += d0 * d2
        c12 += d1 * d2
    # Cholesky of the 3 x 3 covariance; a direction without spread (the compass world's
    # drift, a single surviving ancestor) gets no jitter
    l00 = math.sqrt(c00 / n) if c00 > 0.0 else 0.0
    l10 = c01 / n / l00 if l00 > 0.0 else 0.0
    l20 = c02 / n / l00 if l00 > 0.0 else 0.0
    r = c11 / n - l10 * l10
    l11 = math.sqrt(r) if r > 0.0 else 0.0
    l21 = (c12 / n - l20 * l10) / l11 if l11 > 0.0 else 0.0
    r = c22 / n - l20 * l20 - l21 * l21
    l22 = math.sqrt(r) if r > 0.0 else 0.0
    for i in range(n):
        x_old[i], y_old[i], eta_old[i] = x[i], y[i], eta[i]
        z0, z1, z2 = rng.standard_normal(), rng.standard_normal(), rng.standard_normal()
        x[i] += h * l00 * z0
        y[i] += h * (l10 * z0 + l11 * z1)
        eta[i] += h * (l20 * z0 + l21 * z1 + l22 * z2)
    _nearest_walls(walls, x, y, best, nearest, crossings)
    for i in range(n):
        if int(crossings[i]) % 2 == 0 or best[i] < min_clearance * min_clearance:
            x[i], y[i], eta[i] = x_old[i], y_old[i], eta_old[i]


@numba.njit(cache=True, nogil=True)
def _grown(a, size):
    """A copy of ``a`` in an array of ``size`` elements (the rest uninitialised)."""
    out = np.empty(size, dtype=a.dtype)
    out[:a.size] = a
    return out


@numba.njit(cache=True, nogil=True)
def _snapshot(k, x, y, w, eta, arena, snap_xy, snap_w, snap_eta, snap_arena):
    """Store the first ``snap_w.shape[1]`` particles in snapshot ``k`` (none if k < 0)."""
    if k < 0:
        return
    for i in range(snap_w.shape[1]):
        snap_xy[k, i, 0], snap_xy[k, i, 1] = x[i], y[i]
        snap_w[k, i] = w[i]
        snap_eta[k, i] = eta[i]
        snap_arena[k, i] = arena[i]


@numba.njit(cache=True, nogil=True)
def _allocate(mass, n, floor, u, out):
    """Particles per arena after resampling, ``out (A,)`` summing to ``n``: ``floor`` for
    every arena with non-zero posterior mass (fewer if they do not fit), the rest in
    proportion to the masses by systematic sampling (offset ``u`` in [0, 1))."""
    alive = 0
    for a in range(mass.size):
        if mass[a] > 0.0:
            alive += 1
    floor = min(floor, n // max(alive, 1))
    rest = n - floor * alive
    total = 0.0
    for a in range(mass.size):
        total += mass[a]
    cum = 0.0
    given = 0
    for a in range(mass.size):
        cum += mass[a]
        upto = min(int(cum / total * rest + u), rest) if a < mass.size - 1 else rest
        out[a] = (upto - given) + (floor if mass[a] > 0.0 else 0)
        given = upto


@numba.njit(cache=True, inline="always")
def _wall_distance(wall, px, py):
    rx, ry = px - wall[0], py - wall[1]
    u = min(max((rx * wall[2] + ry * wall[3]) * wall[4], 0.0), 1.0)
    qx, qy = rx - u * wall[2], ry - u * wall[3]
    return math.sqrt(qx * qx + qy * qy)


@numba.njit(cache=True, nogil=True)
def _contact_likelihood(walls, heading, angle, path_length, contact_args, distance, eta,
                        xs, ys, xe, ye, lik):
    r"""``lik[i] = sum_k p(beta | k, heading - eta_i) N(d; d_ik, sd_ik^2)`` for particles
    moving from ``(xs, ys)`` to ``(xe, ye)`` in one arena (``walls (V, 8)``), ``d_ik`` the
    apex of their V against wall ``k`` (:mod:`~hippo_probe.baselines.contact`). Walls
    beyond the angle cutoff, and walls the path stays more than ``_BAND`` s.d. beyond
    the sensed distance, are skipped (their terms are below 1e-14 of the peak).

    The second test needs the wall's terms, but a bound on them settles most walls:
    ``|reach| <= |path_length|``, and ``sd`` is at most ``sd_max``, its value with the
    spread :math:`\epsilon^2 \cos^2\beta + v_\beta \sin^2\beta` replaced by
    :math:`\max(\epsilon^2, v_\beta)`. So a wall farther from the path's end than
    ``distance + |path_length| + _BAND sd_max`` cannot explain the sensed distance within
    ``_BAND`` s.d. and fails the test; it is skipped before its exponential and
    trigonometry are computed, and the sums equal those over every wall. The bound is
    widened by a nanometre and 1e-12 of itself for rounding (enough for coordinates up to
    kilometres). Particles with the same heading as the one before (every particle of the
    compass world when the start heading is known: their drift hypotheses stay 0) reuse
    its walls' terms."""
    angle_obs_var, angle_wall_var, distance_var, path_length_error, cutoff = contact_args
    beta_var = angle_obs_var * angle_wall_var / (angle_obs_var + angle_wall_var)
    sd_max = math.sqrt(distance_var + 0.25 * path_length ** 2
                       * max(path_length_error ** 2, beta_var))
    too_far = distance + abs(path_length) + _BAND * sd_max
    too_far += 1e-9 + 1e-12 * abs(too_far)
    n_walls = walls.shape[0]
    terms = np.empty((n_walls, 3))
    terms_of = np.full(n_walls, -1)     # the particle whose heading the terms are for
    source = -1                         # the first particle with the current heading
    for i in range(xe.size):
        total = 0.0
        h = heading - eta[i]
        if i == 0 or h != heading - eta[i - 1]:
            source = i
        for k in range(n_walls):
            end = _wall_distance(walls[k], xe[i], ye[i])
            if end > too_far:
                continue
            if terms_of[k] != source:
                terms[k, 0], terms[k, 1], terms[k, 2] = wall_terms(
                    walls[k, 7], h, angle, path_length, angle_obs_var, angle_wall_var,
                    distance_var, path_length_error, cutoff)
                terms_of[k] = source
            weight, reach, sd = terms[k, 0], terms[k, 1], terms[k, 2]
            if weight == 0.0:
                continue
            if end - 0.5 * reach > distance + 0.5 * reach + _BAND * sd:
                continue
            start = _wall_distance(walls[k], xs[i], ys[i])
            apex = min(0.5 * (start + end - reach), start, end)
            z = (distance - apex) / sd
            if abs(z) < _BAND:
                total += weight / (_SQRT2PI * sd) * math.exp(-0.5 * z * z)
        lik[i] = total


_SQRT2PI = math.sqrt(2.0 * math.pi)

#: Half-width, in s.d. of the contact distance, of the band where the contact likelihood
#: is evaluated (exp(-8^2/2) ~ 1e-14).
_BAND = 8.0
