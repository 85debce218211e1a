"""Every constant of the Bayesian baselines, in one place, with its reason.

The baselines invert the world's generative model
(:class:`~hippo_probe.world.config.NoiseModel`, :class:`~hippo_probe.world.config.MotionConfig`,
:class:`~hippo_probe.world.config.SensorConfig`); those numbers are imported from the task's
configuration, never repeated here. What lives here are the baselines' own choices: particle
counts, resampling, and the few approximations of the contact process, each with the
measurement that justifies it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .._validators import check_number, check_positive


@dataclass(frozen=True)
class ContactModelConfig:
    """How the baselines read a boundary contact (model: :mod:`~hippo_probe.baselines.contact`).

    The numbers below were checked against the world itself: 23,200 contacts of 300
    generalized-task trials, with the touched wall and the noise-free contact known.

    Attributes
    ----------
    distance_slop_sd : float
        0.003 m, added in quadrature to the sensor's distance noise: speed and heading
        changes within a step bend the path away from the straight "V" of the model.
    path_length_error : float
        0.2: relative error of the step's path length taken from the sensed displacements
        (each has an 18% speed error; a reflection shortens the chord). With these two
        values the deciles of the distance likelihood's probability integral transform
        lie within 0.084-0.105 apart from the lowest (0.125) (chi-square 239 on 9 d.o.f.
        for 23,200 contacts; 0.1 gives 1,519, 0.3 gives 1,286).
    outlier_probability : float
        0.01: probability that a contact is not explained by one reflection off one wall
        (double contacts in corners, large turns after the reflection). Measured: 1.1% of
        contacts lie beyond the 1e-5 quantile of the distance likelihood. Such a
        contact keeps a likelihood floor instead of killing every particle.
    outlier_near_walls : bool
        True (the default): the outlier floor is given only to particles whose step
        could have reached a wall (the distances of its start and end to their nearest
        walls sum to at most ``2 touch_range + max_speed * network_dt``, exact since a
        distance to a wall changes no faster than the path's length); farther from every
        wall a contact is impossible, not merely unexplained. False (the earlier model):
        every particle gets the floor, and a first contact under a broad posterior
        (localization task, start unknown) leaves much of the mass in the arena's
        interior, so the filter is under-confident there (at 10,000 particles,
        Mahalanobis rank at the first contact: top decile 0.037, KS p < 1e-4 on 602
        validation trials; near walls only 0.085, p = 0.16;
        ``analyses/pf_first_contact.py``).
    angle_cutoff : float
        6 standard deviations: walls whose normal disagrees more with the sensed angle get
        zero angle likelihood, so the particle kernels skip them (exp(-18) ~ 1.5e-8 of the
        peak, far below the outlier floor).
    single_hypothesis_gate : float
        2 standard deviations: the single-hypothesis baseline resets onto walls whose
        normal agrees this well with the sensed angle (95% of true walls).
    """

    distance_slop_sd: float = 0.003
    path_length_error: float = 0.2
    outlier_probability: float = 0.01
    outlier_near_walls: bool = True
    angle_cutoff: float = 6.0
    single_hypothesis_gate: float = 2.0

    def __post_init__(self):
        check_number("distance_slop_sd", self.distance_slop_sd, low=0, low_inclusive=True)
        check_number("path_length_error", self.path_length_error, low=0, low_inclusive=True)
        check_number("outlier_probability", self.outlier_probability, low=0,
                     low_inclusive=True, high=1, high_inclusive=False)
        if not isinstance(self.outlier_near_walls, bool):
            raise TypeError(f"`outlier_near_walls` must be True or False; got "
                            f"{self.outlier_near_walls!r}")
        check_positive("angle_cutoff", self.angle_cutoff)
        check_positive("single_hypothesis_gate", self.single_hypothesis_gate)


@dataclass(frozen=True)
class ParticleFilterConfig:
    r"""The particle filters (oracular PF and PF-SLAM).

    Attributes
    ----------
    n_particles : int
        1,000 particles per trial for the oracular PF where the start is known (the
        study's count). Measured in the darkness world on the same 100 test trials
        (``analyses/pf_convergence.py``), 1,000 particles err within 3% of 10,000 at 50 /
        100 / 200 s in the generalized and specialized tasks, except the generalized task
        at 100 s (0.043 vs 0.039 m, 9%; on 300 trials 1,000 err 2-4% above 5,000).
    unknown_start_particles : int
        2,000 where the start is unknown (localization: particles start spread over the
        whole 1 m arena and the posterior stays multimodal until contacts and the drift
        settle it). Chosen when the contact's outlier floor went to every particle: on
        the same 100 test trials of the darkness world, 1,000 particles erred 11% above
        10,000 at 100 s, 2,000 within 4%. With the floor near walls only (the default) 1,000 / 2,000 / 10,000 particles err 0.109 / 0.102 / 0.109 m,
        0.126 / 0.123 / 0.123 m and 0.126 / 0.130 / 0.125 m at 50 / 100 / 200 s; 2,000
        is kept because the posterior's Monte Carlo over-confidence shrinks with the
        particles (analyses/README.md).
    slam_particles : int
        10,000 particles per trial for PF-SLAM: 100 per arena hypothesis at the start, the
        top of the issue's 100-10,000 range, so the true arena keeps particles until its
        evidence accumulates.
    resample_threshold : float
        0.5: systematic resampling when the effective sample size
        ``1 / sum(w_i^2)`` falls below half the particle count, the usual rule (Doucet &
        Johansen 2009, "A tutorial on particle filtering and smoothing", sec. 3.5).
    arena_floor : float
        0.1: PF-SLAM resamples arena by arena and keeps at least this fraction of its
        initial share (10 of the 100 particles per arena at 10,000 particles) for every
        arena whose posterior is not exactly zero, each such particle carrying its
        arena's mass divided among them (the posterior is unchanged). On the 1,000 test
        trials, plain systematic resampling lost the true arena for good in 33 trials,
        all within the first 30 s (a rare early path-integration error leaves the true
        arena's ~100 particles away from the truth at the first contacts, its
        probability drops to ~1e-4 and its last particles die); with the floor, 18.
    intermediate_checks : int
        1: besides the step's end, the absence of contact is also checked at its midpoint
        (on the chord from start to end, heading turned back by half the sensed turn).
        Checking all 7 interior fine steps, as the simulator does, doubled the filter's
        cost (152 vs 82 ns per particle-step) and changed neither its error (35.5 vs
        35.4 mm) nor its calibration measurably (generalized task, 8-150 trials).
    contact_proposals : int
        1 (the default): at a contact step each particle moves once. ``m > 1``:
        each particle first splits into ``m`` children of a ``1/m`` share of its weight
        that move independently, the sharp contact likelihood weighs all of them, and
        resampling returns to the particle count (an unbiased step: the children sample
        the same proposal, ``m`` times as densely). The contact likelihood is narrow (the
        sensed distance to ~6 mm) next to one step's motion noise (~1.5 cm), so with one
        move per particle most particles die at a contact and resampling duplicates the
        few survivors: the default filter's position posterior is too narrow 2-20 s after
        contacts (analyses/README.md). Costs about ``m``
        times a plain step at the ~5% of steps with a contact. Measured (1,000
        validation trials per task, default counts, with ``outlier_near_walls``), m = 10
        barely changes that: the 90% region (rank < 0.9) holds 0.878 (localization, Mahalanobis;
        0.874 with m = 1) and 0.891-0.897 (generalized), and the top Mahalanobis decile
        stays at 0.11-0.13. The over-confidence is therefore not made at the contact
        step itself; it is not the default.
    regularization : float
        0 with a known start (the generalized and specialized tasks, and PF-SLAM): plain
        resampling. ``h > 0``: after each resampling every particle moves by a Gaussian
        kernel of covariance :math:`h^2 \Sigma` (h times the s.d.), :math:`\Sigma` its
        arena's particle covariance of (x, y, drift) (regularized particle filter,
        Musso, Oudjane & Le Gland 2001), so that the duplicates of a few survivors spread
        out again; a move out of the arena, or nearer a wall than ``min_clearance``, is
        undone. Away from walls each resampling widens the posterior by a factor
        :math:`\sqrt{1 + h^2}` (less near walls, where moves are undone), which the next
        observations narrow again; the kernel does not shrink towards the mean (Liu &
        West 2001), so part of what it adds is variance. The small-arena filters are
        calibrated without it, and h = 0.36 (Musso's bandwidth below, for their 1,000
        particles) makes them under-confident: 90% regions 0.906-0.919, pooled KS
        p < 0.02, on 300 validation trials each.
    unknown_start_regularization : float
        0.3 where the start is unknown (the localization task), with the start heading
        known (``oriented``; with an unknown one the drift hypotheses span the circle,
        where a linear kernel on the drift is meaningless, and none is used). The plain
        filter's position posterior there is too narrow at 2,000 particles (sample
        impoverishment 2-20 s after contacts). On the same 300 validation trials of the
        darkness world, h = 0 / 0.1 / 0.2 / 0.3 put 0.870 / 0.882 / 0.888 / 0.898 of the
        truths in the Mahalanobis 90% region (per-time KS p 0.005 / 0.014 / 0.045 /
        0.12; the drift's 0.902 / 0.899 / 0.906 / 0.914, p 0.087 / 0.034 / 0.067 /
        0.064); plain 20,000 particles on the same trials 0.895 (p 0.023). It also
        brings the error to the converged filter's: on 300 test trials (``analyses/
        pf_convergence.py``) h = 0.3 errs 0.124 / 0.117 / 0.125 m at 50 / 100 / 200 s,
        plain 2,000 particles 0.125 / 0.119 / 0.136 and plain 20,000 0.121 / 0.116 /
        0.125. 0.3 is about the bandwidth Musso et al. derive for a Gaussian density of
        ``d`` = 3 dimensions sampled by ``N`` = 2,000 particles,
        :math:`(4 / (N (d + 2)))^{1/(d + 4)} = 0.33`. One covariance for the whole cloud
        blurs a multimodal posterior; the trials start oriented, so only the position
        can be multimodal, early in a trial, and the calibration above holds from 10 s.
    """

    n_particles: int = 1000
    unknown_start_particles: int = 2000
    slam_particles: int = 10_000
    resample_threshold: float = 0.5
    arena_floor: float = 0.1
    intermediate_checks: int = 1
    contact_proposals: int = 1
    regularization: float = 0.0
    unknown_start_regularization: float = 0.3

    def __post_init__(self):
        check_positive("n_particles", self.n_particles, integer=True)
        check_positive("unknown_start_particles", self.unknown_start_particles, integer=True)
        check_positive("slam_particles", self.slam_particles, integer=True)
        check_number("resample_threshold", self.resample_threshold, low=0, high=1)
        check_number("arena_floor", self.arena_floor, low=0, low_inclusive=True, high=1)
        check_number("intermediate_checks", self.intermediate_checks, low=0,
                     low_inclusive=True, integer=True)
        check_positive("contact_proposals", self.contact_proposals, integer=True)
        check_number("regularization", self.regularization, low=0, low_inclusive=True)
        check_number("unknown_start_regularization", self.unknown_start_regularization,
                     low=0, low_inclusive=True)


@dataclass(frozen=True)
class NaiveBayesConfig:
    """The naive-Bayes baseline (path integration times a learnt prior over targets).

    Attributes
    ----------
    prior_trials : int
        2,000 training-split trials estimate the prior of the target at each time step
        (~22,000 samples per step with the time window below).
    prior_split : str
        "train": the prior is learnt from the data a network trains on, never from the
        split it is evaluated on.
    grid_size : int
        64 x 64 grid cells over the range of the training targets (2.8 cm cells for the
        0.33 m arenas, 5 cm for the 1 m arena); the prior is a Gaussian kernel density
        with one kernel per cell of width one cell, so the result is smooth in the
        estimate and tends to path integration when its variance is below a cell.
    time_window : int
        5: the prior at step t pools the targets of steps t-5 ... t+5 (4 s), which
        changes little over that time once the start is seconds past (fewer steps
        before t = 5, where it does change quickly).
    """

    prior_trials: int = 2000
    prior_split: str = "train"
    grid_size: int = 64
    time_window: int = 5

    def __post_init__(self):
        check_positive("prior_trials", self.prior_trials, integer=True)
        check_number("grid_size", self.grid_size, low=4, low_inclusive=True, integer=True)
        check_number("time_window", self.time_window, low=0, low_inclusive=True,
                     integer=True)


@dataclass(frozen=True)
class BaselineConfig:
    """Everything that defines the baselines.

    Attributes
    ----------
    start_prior_samples : int
        20,000 Monte Carlo draws give the mean of an arena's start prior (where path
        integration starts when the start is unknown) to ~3 mm in the 1 m arena.
    """

    contact: ContactModelConfig = field(default_factory=ContactModelConfig)
    particle_filter: ParticleFilterConfig = field(default_factory=ParticleFilterConfig)
    naive_bayes: NaiveBayesConfig = field(default_factory=NaiveBayesConfig)
    start_prior_samples: int = 20_000

    def __post_init__(self):
        check_positive("start_prior_samples", self.start_prior_samples, integer=True)


#: Tags that keep each method's random numbers apart from the others' and from the world's:
#: trial ``i`` of a method draws from ``SeedSequence([seed, STREAM_TAGS[method], i])``, so
#: its result does not depend on how trials are batched or threaded.
STREAM_TAGS = {"particle_filter": 7001, "pf_slam": 7002, "start_prior": 7003}


#: Times (s) at which baseline errors are reported (those of ``world-stats``).
REPORT_TIMES = (50.0, 100.0, 200.0)
