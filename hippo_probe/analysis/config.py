"""Every default of the analyses, in one place, with its reason.

Each analysis reads its defaults from one frozen dataclass here; a keyword argument of the
public function overrides the default for one call. Values follow the conventions of the
hippocampal literature where one exists (cited), otherwise they are documented choices.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class RecordingConventions:
    """How the analyses read a recording (schema v1).

    Attributes
    ----------
    signed_kinds : tuple of str
        ``activity_kind`` values whose activity is signed (the LSTM's h lies in (-1, 1)).
        Skaggs information and the mean vector length need a non-negative rate, so for
        these kinds each unit's activity is shifted by its minimum over the recording
        (``activity - min``); the shift is stated in the result's attrs.
    spike_kinds : tuple of str
        Kinds whose activity is a spike count per sample: maps are divided by ``dt`` and
        reported in Hz; the Rayleigh test is reported for these only (it assumes
        independent events).
    nonnegative_kinds : tuple of str
        Kinds that are non-negative by definition: their minimum over the recording is not
        tracked (it costs about 15% of a rate-map pass); should their maps or curves show
        negative values all the same, the map's minimum is used for the shift, with a
        warning.
    """

    signed_kinds: tuple = ("lstm_hidden",)
    spike_kinds: tuple = ("spike_count",)
    nonnegative_kinds: tuple = ("spike_count", "rate")


@dataclass(frozen=True)
class RateMapConfig:
    """Defaults of :func:`hippo_probe.analysis.ratemaps`.

    Attributes
    ----------
    n_bins : int
        When ``bin_size`` is None, the longer side of the extent is cut into 32 square
        bins: about 2 cm in the 0.66 m arenas of the generalized and specialized tasks and
        about 6 cm in the 2 m arenas of the localization task; 2-5 cm is the usual range
        for rodent place fields (e.g. Skaggs et al. 1996 used about 3 cm bins).
    sigma : float
        Gaussian smoothing width in units of ``bin_size`` when ``sigma`` is None: one bin,
        the light smoothing customary for displayed maps. Information and selectivity use
        their own defaults (unsmoothed), because smoothing inflates both.
    truncate : float
        The Gaussian kernel is cut at 4 standard deviations (scipy's default).
    min_occupancy : float
        Seconds; bins visited for less are NaN. 0 keeps every visited bin, so an
        unsmoothed map equals the plain occupancy-normalised mean (pynapple, opexebo).
    extent_margin : float
        Fraction of the extent's size added on each side when the extent comes from the
        data, so samples on the boundary fall inside a bin.
    few_samples_ratio : float
        Warn when there are fewer valid samples than this times the number of bins: most
        bins would then be unvisited (NaN).
    """

    n_bins: int = 32
    sigma: float = 1.0
    truncate: float = 4.0
    min_occupancy: float = 0.0
    extent_margin: float = 1e-9
    few_samples_ratio: float = 1.0


@dataclass(frozen=True)
class ShuffleConfig:
    """Circular time-shift shuffles (significance and bias correction).

    Activity is shifted circularly in time against the behaviour, which keeps each
    signal's own temporal structure (the null hypothesis: no relation between the two).

    Attributes
    ----------
    min_shift : float
        Shifts are drawn uniformly from [min_shift, duration - min_shift] seconds, 20 s
        as in e.g. Langston et al. 2010; for recordings shorter than 4 x 20 s the bound
        becomes a quarter of the duration.
    seed : int
        Seed of the shifts, so results are reproducible.
    """

    min_shift: float = 20.0
    seed: int = 0


@dataclass(frozen=True)
class InformationConfig:
    """Defaults of :func:`spatial_information` and :func:`spatial_selectivity`.

    Attributes
    ----------
    sigma : float
        No smoothing (in bins) when the maps are made here: smoothing spreads activity
        into neighbouring bins and biases both measures.
    n_shuffles : int
        0: no shuffle correction unless asked (each shuffle is one pass over the data).
    """

    sigma: float = 0.0
    n_shuffles: int = 0


@dataclass(frozen=True)
class HeadDirectionConfig:
    """Defaults of :func:`head_direction_tuning`.

    Attributes
    ----------
    n_bins : int
        60 bins of 6 degrees, unsmoothed: the convention of the ADn literature (e.g.
        Taube et al. 1990 used 6 degree bins) and of the real session's README.
    n_shuffles : int
        100 circular time shifts: p-values resolve to 1/101.
    """

    n_bins: int = 60
    n_shuffles: int = 100


@dataclass(frozen=True)
class StabilityConfig:
    """Defaults of :func:`place_field_stability`.

    Attributes
    ----------
    min_bins : int
        A correlation over fewer than 5 bins visited in both halves is NaN.
    """

    min_bins: int = 5


@dataclass(frozen=True)
class RemappingConfig:
    """Defaults of :func:`remapping_similarity`.

    Attributes
    ----------
    n_bins : int
        16 bins along the longer side: per-trial maps of a 200 s trial must be well
        sampled (a 500-step trial visits roughly a hundred of 256 bins of 4 cm).
    sigma : float
        One bin of smoothing, so single-trial maps are not dominated by sampling noise.
    min_common_bins : int
        A trial pair sharing fewer than 5 visited bins gives NaN.
    seed : int
        Seed of the label permutation of the control.
    """

    n_bins: int = 16
    sigma: float = 1.0
    min_common_bins: int = 5
    seed: int = 0


@dataclass(frozen=True)
class DecodingConfig:
    """Defaults of :func:`decode_covariance`.

    Attributes
    ----------
    n_folds : int
        5 folds by trial: every trial's samples are predicted by a model that never saw
        that trial.
    alphas : tuple of float
        Ridge penalties searched by an inner cross-validation (by trial) inside each
        training set, in scikit-learn's convention ``||y - Xw||^2 + alpha ||w||^2``.
    """

    n_folds: int = 5
    alphas: tuple = (1e-3, 1e-2, 1e-1, 1.0, 10.0, 100.0, 1e3, 1e4)


@dataclass(frozen=True)
class CorrelationDimensionConfig:
    """Defaults of :func:`correlation_dimension`.

    Attributes
    ----------
    max_points : int
        At most 4,000 points (8 million pairs) are used, drawn at random; pair counts are
        accumulated in blocks so memory stays bounded.
    theiler : int
        Pairs closer in time than 10 samples (within a trial) are excluded: temporally
        adjacent states are close because of continuity, not because of the attractor's
        geometry (Theiler 1986).
    transient : float
        The first 10% of each trial is dropped, so the initial convergence of the network
        state is not counted as part of the attractor.
    per_decade : int
        The pair-count histogram has 50 log-spaced radii per decade: the scaling range is
        then resolved to 2% of a decade.
    decades : int
        It spans 7 decades below the largest possible distance (twice the largest distance
        from the centroid), far below any scaling range a few thousand points can show.
    c_range : tuple of float
        The scaling range is searched where 1e-4 <= C(r) <= 0.1: below, too few pairs;
        above, the finite size of the set bends the curve.
    min_decades : float
        The fit uses the window of at least 0.5 decade of r in that range whose straight-line
        fit has the smallest RMS residual per decade of width.
    block : int
        Rows per block of the pairwise-distance computation (512 x 4,000 distances, 16 MB).
    seed : int
        Seed of the subsampling.
    """

    max_points: int = 4000
    theiler: int = 10
    transient: float = 0.1
    per_decade: int = 50
    decades: int = 7
    c_range: tuple = (1e-4, 0.1)
    min_decades: float = 0.5
    block: int = 512
    seed: int = 0


@dataclass(frozen=True)
class ComputeConfig:
    """How the per-bin sums are computed.

    Attributes
    ----------
    split_every : int
        Partial sums of dask chunks are added 8 at a time (a tree reduction): few enough
        partials alive at once to bound memory, enough to keep the tree shallow.
    min_samples_per_thread : int
        An in-memory recording is split across numba threads only in blocks of at least
        50,000 samples; below that, starting a thread costs more than it saves.
    """

    split_every: int = 8
    min_samples_per_thread: int = 50_000


CONVENTIONS = RecordingConventions()
COMPUTE = ComputeConfig()
RATEMAP = RateMapConfig()
SHUFFLE = ShuffleConfig()
INFORMATION = InformationConfig()
HEAD_DIRECTION = HeadDirectionConfig()
STABILITY = StabilityConfig()
REMAPPING = RemappingConfig()
DECODING = DecodingConfig()
CORRELATION_DIMENSION = CorrelationDimensionConfig()
