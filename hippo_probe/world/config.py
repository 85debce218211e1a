"""Every modelling constant of the simulated world, in one place, with its reason.

The seed study (Kanitscheider & Fiete 2017) gives no numbers for the trajectories, the time
step or the noise; its Supplementary Information is not available. Each value below is
therefore a documented choice, made so that the study's premises hold:

* self-motion alone is not enough: path integration (PI) of the noisy inputs drifts by
  about the arena's radius in a 200 s trial of the small (R = 0.33 m) arenas;
* boundary contacts are informative but rare: seconds apart, each one ambiguous (a
  distance and an angle to *some* wall, not which wall).

``hippo-probe world-stats`` prints the resulting statistics; tests assert them loosely.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .._validators import check_number, check_option, check_positive


@dataclass(frozen=True)
class ArenaConfig:
    """Random star-shaped polygon arenas.

    Attributes
    ----------
    n_vertices : int
        10, as in the study.
    mean_radius : float
        Mean centre-to-vertex length in metres: 1.0 for the localization task, 0.33 for
        the generalized and specialized tasks (study, Fig. 2-3).
    radius_spread : float
        Vertex lengths are drawn ``mean_radius * U(1 - s, 1 + s)`` and then rescaled so
        their mean is exactly ``mean_radius``. 0.4 gives visibly irregular, asymmetric
        arenas (symmetry would make localization impossible) without needle-thin spikes.
    angle_jitter : float
        Vertex polar angles are ``2 pi k / V + offset + U(-j, j) * 2 pi / V``; ``j < 0.5``
        keeps them ordered, which makes the polygon simple and star-shaped about the
        origin (the arena's centre).
    """

    n_vertices: int = 10
    mean_radius: float = 1.0
    radius_spread: float = 0.4
    angle_jitter: float = 0.3

    def __post_init__(self):
        check_number("n_vertices", self.n_vertices, low=3, low_inclusive=True, integer=True)
        check_positive("mean_radius", self.mean_radius)
        check_number("radius_spread", self.radius_spread, low=0, low_inclusive=True,
                     high=0.9)
        check_number("angle_jitter", self.angle_jitter, low=0, low_inclusive=True,
                     high=0.5, high_inclusive=False)


@dataclass(frozen=True)
class MotionConfig:
    """Correlated random walk of the simulated rat.

    Speed and angular velocity are Ornstein-Uhlenbeck processes integrated with an
    Euler-Maruyama step ``fine_dt``; the network senses every ``network_dt``.

    Attributes
    ----------
    fine_dt : float
        0.05 s: short enough that one step (at most ``max_speed * fine_dt`` = 2.5 cm) is
        shorter than the touch range, so a wall is always felt before it is reached.
    network_dt : float
        0.4 s: 500 network steps = 200 s per trial, the study's trial length.
    n_steps : int
        500 network steps per trial.
    mean_speed, speed_sd, speed_tau : float
        0.15 m/s mean running speed (typical of a foraging rat, e.g. Raudies & Hasselmo
        2012 and Cheung et al. 2012 use 0.1-0.2 m/s), stationary s.d. 0.05 m/s, correlation
        time 2 s.
    min_speed, max_speed : float
        Speed is clipped to [0.02, 0.5] m/s: the rat keeps moving and never teleports.
    turn_sd, turn_tau : float
        Angular velocity: stationary s.d. 1.0 rad/s, correlation time 1 s, so the heading
        decorrelates over a few seconds (a few body lengths), as in open-field foraging.
    """

    fine_dt: float = 0.05
    network_dt: float = 0.4
    n_steps: int = 500
    mean_speed: float = 0.15
    speed_sd: float = 0.05
    speed_tau: float = 2.0
    min_speed: float = 0.02
    max_speed: float = 0.5
    turn_sd: float = 1.0
    turn_tau: float = 1.0

    def __post_init__(self):
        for name in ("fine_dt", "network_dt", "mean_speed", "speed_tau", "turn_tau",
                     "max_speed"):
            check_positive(name, getattr(self, name))
        check_positive("n_steps", self.n_steps, integer=True)
        for name in ("speed_sd", "turn_sd", "min_speed"):
            check_number(name, getattr(self, name), low=0, low_inclusive=True)
        ratio = self.network_dt / self.fine_dt
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ValueError(
                f"`network_dt` must be a whole multiple of `fine_dt` ({self.fine_dt}); "
                f"got {self.network_dt}"
            )
        if self.min_speed > self.max_speed:
            raise ValueError(
                f"`min_speed` must be <= `max_speed` ({self.max_speed}); got {self.min_speed}"
            )

    @property
    def substeps(self) -> int:
        """Fine steps per network step."""
        return int(round(self.network_dt / self.fine_dt))

    @property
    def duration(self) -> float:
        """Trial length in seconds."""
        return self.n_steps * self.network_dt


@dataclass(frozen=True)
class SensorConfig:
    """Boundary contact (whisker/body touch) geometry.

    Attributes
    ----------
    touch_range : float
        0.05 m, about a rat's whisker length: contact happens when the agent, heading
        towards the nearest wall, comes closer than this. Larger than one fine step
        (``max_speed * fine_dt`` = 2.5 cm), so the agent never reaches a wall.
    min_clearance : float
        A fine step that would end outside the arena or closer than 5 mm to a wall (only
        possible in sharp corners) is refused: the agent stays put and turns. This is the
        hard guarantee that it never leaves its arena.
    """

    touch_range: float = 0.05
    min_clearance: float = 0.005

    def __post_init__(self):
        check_positive("touch_range", self.touch_range)
        check_number("min_clearance", self.min_clearance, low=0,
                     high=self.touch_range, high_inclusive=False)


#: Heading drift of the darkness world (rad/sqrt(s)); see :attr:`NoiseModel.heading_drift`.
DARKNESS_HEADING_DRIFT = 0.05

@dataclass(frozen=True)
class NoiseModel:
    r"""Noise on every sensed quantity, per network step.

    The structure follows Cheung, Ball, Milford, Wyeth & Wiles (2012), "Maintaining a
    cognitive map in darkness: the need to fuse boundary knowledge with path integration",
    PLoS Comput Biol 8:e1002651: self-motion is corrupted by multiplicative speed noise
    and by heading (direction) noise, so path-integration (PI) error grows without bound
    and only boundary contacts can correct it; boundary contacts themselves are sensed
    with small errors in distance and angle. In darkness the rat's sense of head
    direction itself drifts, as a Wiener process (their model of head-direction cells
    without vision); that drift is :attr:`heading_drift`.

    Generative model, for the true displacement ``D`` over network step ``t`` (a 2-vector
    in the allocentric frame), true heading ``theta_t`` and heading drift ``eta_t``::

        eta_t     = eta_{t-1} + heading_drift * sqrt(dt) * z_t,   eta_0 = 0
        D_obs     = (1 + e_s) * Rot(eta_t + e_r) @ D,   e_s ~ N(0, speed_sd^2),
                                                        e_r ~ N(0, rotation_sd^2)
        hd_obs    = theta_t + eta_t + e_h,              e_h ~ N(0, head_direction_sd^2)
        dhd_obs   = wrap(theta_t - theta_{t-1}) + (eta_t - eta_{t-1}) + e_dh,
                                                        e_dh ~ N(0, turn_sd^2)
        d_obs     = d + e_d,                            e_d ~ N(0, contact_distance_sd^2)
        beta_obs  = beta + e_b,                         e_b ~ N(0, contact_angle_sd^2)

    (``dt`` the network step, ``z_t`` standard normal; every other noise independent
    across steps.) ``eta`` starts at 0 because the rat is oriented when a trial begins.
    The displacement is the rat's own estimate, expressed in its drifting heading frame
    (what its path integrator computes from idiothetic speed and angular velocity); its
    heading sense carries the same drift, and so does the sensed turn (the drift *is*
    the accumulated error of the angular velocity). A contact reports distance ``d`` and
    angle ``beta`` from the touched wall's inward normal to the body axis: touch is
    egocentric and does not drift, so which wall was touched is only as certain as the
    heading is. With ``heading_drift = 0`` the model is the compass world's: heading with
    independent errors and displacements in the allocentric frame.

    Magnitudes: with a mean displacement of 0.06 m per 0.4 s step, the per-step position
    error of the speed and rotation noise is about ``0.06 * sqrt(speed_sd^2 +
    rotation_sd^2)``; summed over 500 independent steps, ``0.06 * 0.25 * sqrt(500) ~ 0.3
    m`` after 200 s, about the radius of the 0.33 m arenas. Head direction has
    independent 0.1 rad errors on top of any drift. Contact distance (0-5 cm) is sensed
    to 5 mm and its angle to 0.2 rad (11 deg): precise, but ambiguous because any wall
    could have been touched. ``hippo-probe world-stats`` prints the measured values.

    Attributes
    ----------
    speed_sd, rotation_sd : float
        0.18 each: relative speed error and rotation (rad) of each sensed displacement.
    head_direction_sd : float
        0.1 rad of independent error on the sensed heading.
    turn_sd : float
        0.05 rad of independent error on the sensed turn.
    contact_distance_sd, contact_angle_sd : float
        0.005 m and 0.2 rad.
    heading_drift : float
        S.d. of the heading drift's Wiener increments, rad/sqrt(s): after ``t`` seconds
        ``eta ~ N(0, heading_drift^2 t)``. 0 in the compass world. The default, the
        darkness world's 0.05 rad/sqrt(s), is calibrated to Cheung et al. (2012), who
        compare their drift model with head-direction cells recorded without vision drifting 5.1-26.6 deg/min
        (19 cells): the absolute drift over a 1-minute window is half-normal with s.d.
        ``0.05 * sqrt(60)`` = 0.39 rad, so its median is ``0.674 * 0.39`` rad = 14.9
        deg/min, the middle of that range. One drift s.d. serves every trial, so the rates
        spread wider than the 19 cells' (whose own drift rates differ): 18% of 1-minute
        windows drift less than 5.1 and 23% more than 26.6 deg/min (half-normal CDF;
        ``hippo-probe world-stats`` prints the simulated distribution). With it, path
        integration alone loses the place within 2-3 minutes, their point. A Wiener
        process has no single "rate": its mean rate over a window of ``w`` seconds falls
        as ``1 / sqrt(w)``; the 1-minute window is this project's reading of "deg/min"
        (the cells' rates were measured over recordings of minutes).
    """

    speed_sd: float = 0.18
    rotation_sd: float = 0.18
    head_direction_sd: float = 0.1
    turn_sd: float = 0.05
    contact_distance_sd: float = 0.005
    contact_angle_sd: float = 0.2
    heading_drift: float = DARKNESS_HEADING_DRIFT

    def __post_init__(self):
        for name in ("speed_sd", "rotation_sd", "head_direction_sd", "turn_sd",
                     "contact_distance_sd", "contact_angle_sd", "heading_drift"):
            check_number(name, getattr(self, name), low=0, low_inclusive=True)

    @classmethod
    def noiseless(cls) -> "NoiseModel":
        """A model with every noise, drift included, set to zero (for tests of exact path
        integration)."""
        return cls(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


#: The named worlds: ``"darkness"`` (the study's, the default) and ``"compass"`` (the first
#: world of this project, kept for the ablation).
WORLDS = ("darkness", "compass")


@dataclass(frozen=True)
class WorldConfig:
    """Everything that defines the world of one task.

    The two named worlds share arenas, motion and sensors and differ only in how heading
    is sensed (:attr:`NoiseModel.heading_drift`): build them with :func:`world_config`.
    ``WorldConfig()`` is the darkness world with the default (1 m) arena.

    Attributes
    ----------
    name : {"darkness", "compass"}
        The world this configuration belongs to (recorded in trial caches, recordings and
        checkpoints). A compass world has no drift (build it with
        ``world_config("compass")``; ``WorldConfig(name="compass")`` with the default,
        drifting noise model is refused); a darkness world may have its drift switched
        off (``heading_drift=0``) for ablations and tests.
    """

    arena: ArenaConfig = field(default_factory=ArenaConfig)
    motion: MotionConfig = field(default_factory=MotionConfig)
    sensors: SensorConfig = field(default_factory=SensorConfig)
    noise: NoiseModel = field(default_factory=NoiseModel)
    name: str = "darkness"

    def __post_init__(self):
        check_option("name", self.name, WORLDS)
        if self.name == "compass" and self.noise.heading_drift != 0:
            raise ValueError(f"the compass world has no heading drift: `heading_drift` must "
                             f"be 0 for name='compass'; got {self.noise.heading_drift} "
                             f"(build it with world_config('compass'))")


def world_config(world="darkness", *, arena: ArenaConfig | None = None) -> WorldConfig:
    """The named world (``"darkness"`` or ``"compass"``), or ``world`` itself if it is a
    :class:`WorldConfig` already.

    Parameters
    ----------
    world : {"darkness", "compass"} or WorldConfig
    arena : ArenaConfig, optional
        The arenas of a named world (default ``ArenaConfig()``); ignored for a given
        :class:`WorldConfig`, which is used exactly as it is.

    Examples
    --------
    >>> world_config("compass").noise.heading_drift
    0.0
    >>> world_config("darkness").noise.heading_drift
    0.05
    """
    if isinstance(world, WorldConfig):
        return world
    if not isinstance(world, str):
        raise TypeError(f"`world` must be one of {WORLDS} or a WorldConfig; got {world!r}")
    check_option("world", world, WORLDS)
    drift = DARKNESS_HEADING_DRIFT if world == "darkness" else 0.0
    return WorldConfig(arena=arena or ArenaConfig(), noise=NoiseModel(heading_drift=drift),
                       name=world)


# Network input features, in column order of ``TrialBatch.inputs``.
FEATURES = (
    "dx",            # noisy displacement over the step, x (m), allocentric axes turned by
    "dy",            # ... the heading drift eta (the rat's own frame); y (m)
    "cos_hd",        # cos of sensed (noisy, drifting) head direction at the end of the step
    "sin_hd",        # sin of sensed head direction
    "dhd",           # sensed change of head direction over the step (rad)
    "contact",       # 1 if the step had a boundary contact, else 0
    "contact_distance",  # noisy distance to the touched wall at contact (m), else 0
    "cos_beta",      # cos of noisy angle from the wall's inward normal to the heading
    "sin_beta",      # sin of that angle; both 0 without contact
)
