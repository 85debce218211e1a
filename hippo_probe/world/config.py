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

from .._validators import check_number, check_positive


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


@dataclass(frozen=True)
class NoiseModel:
    """Noise on every sensed quantity, per network step (independent across steps).

    The structure follows Cheung, Ball, Milford, Wyeth & Wiles (2012), "Maintaining a
    cognitive map in darkness: the need to fuse boundary knowledge with path integration",
    PLoS Comput Biol 8:e1002651: self-motion is corrupted by multiplicative speed noise
    and by heading (direction) noise, so PI error grows without bound (as a random walk,
    ~ sqrt(t)) and only boundary contacts can correct it; boundary contacts themselves are
    sensed with small errors in distance and angle.

    Generative model, for the true displacement ``D`` over a network step (a 2-vector in
    the allocentric frame) and heading ``theta``::

        D_obs     = (1 + e_s) * Rot(e_r) @ D,         e_s ~ N(0, speed_sd^2),
                                                      e_r ~ N(0, rotation_sd^2)
        hd_obs    = theta + e_h,                      e_h ~ N(0, head_direction_sd^2)
        dhd_obs   = wrap(theta_t - theta_{t-1}) + e_dh, e_dh ~ N(0, turn_sd^2)
        d_obs     = d + e_d,                          e_d ~ N(0, contact_distance_sd^2)
        beta_obs  = beta + e_b,                       e_b ~ N(0, contact_angle_sd^2)

    Magnitudes: with a mean displacement of 0.06 m per 0.4 s step, the per-step position
    error is about ``0.06 * sqrt(speed_sd^2 + rotation_sd^2)``; summed over 500
    independent steps the expected PI error after 200 s is of order
    ``0.06 * 0.25 * sqrt(500) ~ 0.3 m``, i.e. about the radius of the 0.33 m arenas (the
    regime where boundaries matter, as Cheung et al. argue for rats in darkness; the
    measured value is printed by ``hippo-probe world-stats``). Head direction is given
    with independent 0.1 rad errors and no drift (the study provides the allocentric
    frame). Contact distance (0-5 cm) is sensed to 5 mm and its angle to 0.2 rad (11 deg):
    precise, but ambiguous because any wall could have been touched.
    """

    speed_sd: float = 0.18
    rotation_sd: float = 0.18
    head_direction_sd: float = 0.1
    turn_sd: float = 0.05
    contact_distance_sd: float = 0.005
    contact_angle_sd: float = 0.2

    def __post_init__(self):
        for name in ("speed_sd", "rotation_sd", "head_direction_sd", "turn_sd",
                     "contact_distance_sd", "contact_angle_sd"):
            check_number(name, getattr(self, name), low=0, low_inclusive=True)

    @classmethod
    def noiseless(cls) -> "NoiseModel":
        """A model with every noise set to zero (for tests of exact path integration)."""
        return cls(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


@dataclass(frozen=True)
class WorldConfig:
    """Everything that defines the world of one task."""

    arena: ArenaConfig = field(default_factory=ArenaConfig)
    motion: MotionConfig = field(default_factory=MotionConfig)
    sensors: SensorConfig = field(default_factory=SensorConfig)
    noise: NoiseModel = field(default_factory=NoiseModel)


# Network input features, in column order of ``TrialBatch.inputs``.
FEATURES = (
    "dx",            # noisy displacement over the step, allocentric x (m)
    "dy",            # noisy displacement over the step, allocentric y (m)
    "cos_hd",        # cos of noisy head direction at the end of the step
    "sin_hd",        # sin of noisy head direction
    "dhd",           # noisy change of head direction over the step (rad)
    "contact",       # 1 if the step had a boundary contact, else 0
    "contact_distance",  # noisy distance to the touched wall at contact (m), else 0
    "cos_beta",      # cos of noisy angle from the wall's inward normal to the heading
    "sin_beta",      # sin of that angle; both 0 without contact
)
