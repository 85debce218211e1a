"""Every default of the analyses, in one place, with its reason.

Each analysis reads its defaults from one frozen dataclass here; a keyword argument of the
public function overrides the default for one call. Values follow the conventions of the
hippocampal literature where one exists (cited), otherwise they are documented choices.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..recording.schema import SIGNED_KINDS


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
    noise_free_kinds : tuple of str
        Kinds without counting noise (a network's units): with many samples any tuning at
        all beats time-shift shuffles, so :func:`~hippo_probe.analysis.classify_cells`
        warns on them and points to :func:`hippo_probe.poisson_spikes`.
    probability_tolerance : float
        How far a sample's class probabilities may sum from 1 (1e-3: a float32 softmax
        over 100 classes is off by ~1e-6; all zeros, logits or percentages are off by far
        more).
    """

    signed_kinds: tuple = SIGNED_KINDS
    noise_free_kinds: tuple = ("lstm_hidden",)
    spike_kinds: tuple = ("spike_count",)
    nonnegative_kinds: tuple = ("spike_count", "rate")
    probability_tolerance: float = 1e-3


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
        their own defaults (unsmoothed), because smoothing biases both (it spreads a
        field: a sharp field's information falls, a noisy map's rises).
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
    outlier_fraction, outlier_stretch : float
        When the extent comes from the positions, warn if the ``outlier_fraction`` (1%)
        of samples at either end of an axis stretch it more than ``outlier_stretch``
        (1.5) times the span of the rest: a few far tracking glitches would otherwise
        coarsen every bin and wash out place fields. Pass ``extent=`` to choose the bins.
    """

    n_bins: int = 32
    sigma: float = 1.0
    truncate: float = 4.0
    min_occupancy: float = 0.0
    extent_margin: float = 1e-9
    few_samples_ratio: float = 1.0
    outlier_fraction: float = 0.01
    outlier_stretch: float = 1.5


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
    max_unvisited_arc : float
        Degrees. The mean vector length (and its p-values) is NaN where the head
        direction left an arc of unvisited bins longer than this, i.e. where every
        direction visited lies within a shorter arc: over a short arc every curve has a
        long mean vector, whatever the cell does (a stuck or misread sensor visits one
        bin and gives R = 1). Half the circle. Sparse but spread headings (a few discrete
        directions, a coarsely quantised tracker) keep their R. Over half the circle an
        untuned curve still reads R up to 2/pi: ``attrs['untuned_length']`` gives it, and the
        shuffles' p-values account for it.
    """

    n_bins: int = 60
    n_shuffles: int = 100
    max_unvisited_arc: float = 180.0


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
class EnvironmentDecodingConfig:
    """Defaults of :func:`decode_environment`.

    Attributes
    ----------
    times : tuple of float
        Decoded at 50, 100 and 200 s into the trial: the times at which the study reads
        its classification curves (Fig. 3C, 3F).
    c : float
        Inverse L2 strength of the logistic regression on standardized units
        (scikit-learn's ``C``); 1, the middle of the range that gave the same test
        accuracies on the networks (0.01-100, ``analyses/arena_probe.py``).
    window : int
        Training samples at each time: the step and its 2 neighbours on each side (5
        samples per trial), so a fit at one moment sees 5x the trials' worth of data.
    n_folds : int
        5 folds by trial when no separate test recording is given.
    max_iter : int
        Iterations of the solver (lbfgs): 1,000, enough to converge on 256 units.
    """

    times: tuple = (50.0, 100.0, 200.0)
    c: float = 1.0
    window: int = 2
    n_folds: int = 5
    max_iter: int = 1000


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


@dataclass(frozen=True)
class PlaceFieldConfig:
    """Defaults of :func:`hippo_probe.analysis.place_fields`.

    Attributes
    ----------
    threshold : float
        A field is a contiguous set of bins whose rate exceeds 20% of the map's range above
        its minimum, ``min + 0.2 (peak - min)``; for spike maps (minimum about 0) this is
        the customary 20% of the peak rate of the place-cell literature. The range, not the
        peak alone, makes the rule offset-invariant, so it applies to the LSTM's signed h.
    min_bins : int
        Fields of fewer than 9 bins are noise (opexebo's and the BNT's
        ``firing_field_min_bins``).
    min_peak : float or None
        Minimum peak rate of a field, in the map's units; None = none (an absolute rate has
        no meaning for network activity, whose h may peak below 0; use e.g. 1 Hz for
        spikes, opexebo's default).
    connectivity : int
        Bins touching by an edge (1, 4-connectivity) or also by a corner (2,
        8-connectivity) belong to one field (``scipy.ndimage.generate_binary_structure``);
        4-connectivity, as opexebo and the BNT.
    """

    threshold: float = 0.2
    min_bins: int = 9
    min_peak: float | None = None
    connectivity: int = 1


@dataclass(frozen=True)
class GridConfig:
    """Defaults of :func:`hippo_probe.analysis.grid_score`.

    Attributes
    ----------
    min_overlap : int
        Lags of the spatial autocorrelogram with fewer than 20 bins visited in both the map
        and its shifted copy are NaN: their correlation rests on too few bins
        (Sargolini et al. 2006; Hafting et al. 2005).
    central_threshold : float
        The central peak of the autocorrelogram is the connected region around zero lag
        where r > 0.1; its radius is that of the disc of the same area (floored to whole
        bins, as the BNT/opexebo) and is excluded from the annulus.
    peak_threshold : float
        The peaks around the centre (for spacing, orientation and the ``"peaks"`` annulus)
        are local maxima of the autocorrelogram with r > 0.1 (opexebo's threshold).
    min_orientation : float
        Of two peaks in directions less than 15 degrees apart, the farther is dropped
        (opexebo/BNT ``min_orientation``): it belongs to the next ring.
    max_radius : float
        The annulus' outer radius reaches at most 0.9 x the shorter side of the map (in
        bins): opexebo/BNT keep the lags of 80% overlap, whose half-width is 0.9 sides.
    max_central : float
        The central peak's radius must be less than half the largest outer radius, else the
        grid score is NaN: the first ring of a grid's peaks lies at about twice the central
        radius or more, so a wider central peak (a broad or ramp-like map, common in
        networks) leaves only a thin ring of the most extreme lags, whose "score" is noise.
    window : int
        The ``"sweep"`` annulus: gridness of every outer radius, averaged over 3
        consecutive radii, maximum taken (Langston et al. 2010 as in the BNT and opexebo,
        ``numGridnessRadii = 3``).
    min_outer : int
        The sweep's first outer radius is the central radius + 1 bin, and at least 3 bins
        (the BNT and opexebo): a thinner ring holds too few lags for a correlation.
    annulus : str
        ``"sweep"`` (Langston et al. 2010; BNT, opexebo) or ``"peaks"`` (Sargolini et al.
        2006: the annulus reaches the six peaks around the centre plus one central radius).
    sigma : float
        Gaussian smoothing of the maps (bins) when made here: one bin, as displayed maps.
    """

    min_overlap: int = 20
    central_threshold: float = 0.1
    peak_threshold: float = 0.1
    min_orientation: float = 15.0
    max_radius: float = 0.9
    max_central: float = 0.5
    window: int = 3
    min_outer: int = 3
    annulus: str = "sweep"
    sigma: float = 1.0


@dataclass(frozen=True)
class BorderConfig:
    """Defaults of :func:`hippo_probe.analysis.border_score`.

    Attributes
    ----------
    threshold : float
        Fields for the border score are contiguous bins above 30% of the map's range above
        its minimum (of the peak, for spike maps), Solstad et al. 2008.
    min_area : float
        ... covering at least 200 cm^2 (0.02 m^2), Solstad et al. 2008; never fewer than
        ``min_bins`` bins.
    min_bins : int
        A field has at least 2 bins, whatever the bin size.
    search_width : int
        A wall's coverage looks up to 8 bins inwards (along the wall's normal) for the
        first visited bin (opexebo/BNT ``search_width``): unvisited bins along a wall do not
        break a field's contact with it.
    merge_angle : float
        Consecutive polygon edges turning by less than 30 degrees (from the wall's first
        edge) are one wall: the random star-shaped arenas have many nearly collinear
        edges, and Solstad's coverage is per straight side.
    min_wall_bins : int
        A wall shorter than 4 bins is not used for coverage (a corner-sized wall is covered
        by any field in the corner); it still bounds the arena for distances.
    sigma : float
        Gaussian smoothing of the maps (bins) when made here.
    min_hull_coverage : float
        Walls estimated from the occupancy (the convex hull of the visited bins) are
        warned about when the visited bins fill less than half of that hull: the session
        was on a maze or track (the shipped mouse's Y-maze: 28%), whose hull's edges cross
        space the animal never entered, not an open field's walls (a foraging session
        fills most of it).
    """

    threshold: float = 0.3
    min_area: float = 0.02
    min_bins: int = 2
    search_width: int = 8
    merge_angle: float = 30.0
    min_wall_bins: int = 4
    sigma: float = 1.0
    min_hull_coverage: float = 0.5


@dataclass(frozen=True)
class SpeedConfig:
    """Defaults of :func:`hippo_probe.analysis.speed_score` (Kropff et al. 2015).

    Attributes
    ----------
    sigma : float
        Activity and speed are smoothed in time, within trials, by a Gaussian of 0.25 s
        s.d. (Kropff et al. 2015: 250 ms) before they are correlated; 0 = none.
    min_speed, max_speed : float
        Only samples with a speed in [0.02, 0.5] m/s count (Kropff et al. 2015: 2-50 cm/s):
        rest and implausible tracking jumps are left out.
    block : int
        Samples per block of the correlation of activity with the shifted speeds (memory
        ``block x n_shuffles`` floats).
    """

    sigma: float = 0.25
    min_speed: float = 0.02
    max_speed: float = 0.5
    block: int = 8192


@dataclass(frozen=True)
class ConjunctiveConfig:
    """Defaults of :func:`hippo_probe.analysis.conjunctive_tuning`.

    Attributes
    ----------
    n_bins : int
        16 spatial bins along the extent's longer side and ...
    n_directions : int
        ... 12 head-direction bins of 30 degrees: the joint (position x direction) map has
        16 x 16 x 12 cells, each of which needs samples (Burgess et al. 2005 used similarly
        coarse bins for the factorial model).
    n_iterations, tolerance : int, float
        The factorial model is iterated until the factors change by less than 1e-5
        (relative) or 500 times (it converges linearly; on the mouse session's units 50
        iterations left changes of up to 1.5e-3).
    batch : int
        Shuffles whose joint sums are held at once (memory ``batch x units x cells``).
    """

    n_bins: int = 16
    n_directions: int = 12
    n_iterations: int = 500
    tolerance: float = 1e-5
    batch: int = 10


@dataclass(frozen=True)
class CellClassConfig:
    """Defaults of :func:`hippo_probe.analysis.classify_cells` and of the shuffles of the
    cell-class scores.

    A unit belongs to a class when its score exceeds the given percentile of its own
    time-shift shuffles (``threshold="unit"``) or of all units' shuffles pooled
    (``threshold="pooled"``, the papers' practice).

    Attributes
    ----------
    n_shuffles : int
        100 circular time shifts (each at least ``ShuffleConfig.min_shift``), as
        Langston et al. 2010 and Kropff et al. 2015; p-values resolve to 1/101.
    grid_percentile : float
        Grid cells: grid score above the 95th percentile of the shuffles (Langston et al.
        2010; Wills et al. 2010; Boccara et al. 2010).
    border_percentile, border_min_score : float
        Border cells: border score above the 99th percentile of the shuffles (Bjerknes et
        al. 2014; Kropff et al. 2015) and above 0.5 (Solstad et al. 2008).
    place_percentile : float
        Place cells: Skaggs information (unsmoothed map) above the 95th percentile of the
        shuffles (Langston et al. 2010; Wills et al. 2010) and at least one place field.
    hd_percentile : float
        Head-direction cells: mean vector length above the 99th percentile of the
        shuffles (Boccara et al. 2010).
    speed_percentile : float
        Speed cells: speed score above the 99th percentile of the shuffles (Kropff et al.
        2015); positive speed cells only.
    conjunctive_percentile : float
        Conjunctive (position x direction) cells: both factors of the factorial model
        (Burgess et al. 2005) above the 99th percentile of their shuffles.
    spatial_gate : bool
        Grid and border cells must also carry significant spatial information (above
        ``place_percentile`` of its shuffles): the score of a spatially flat map is noise,
        and each per-unit test alone lets through its nominal 5% (grid) of such maps.
    factorial_gate : bool
        Place cells must keep significant information in the position factor of the
        factorial (position x direction) model, and head-direction cells a significant
        direction factor, each above its class's percentile (Burgess et al. 2005): where
        position and direction are sampled together (wall following, small arenas), a
        head-direction cell has a structured rate map and a place cell a tuned
        direction curve; the model explains each away.
    threshold : str
        ``"unit"`` (each unit against its own shuffles) or ``"pooled"``.
    precedence : tuple of str
        The single ``cell_class`` label of a unit in several classes: the first class of
        this list it belongs to (the boolean columns keep every membership).
    """

    n_shuffles: int = 100
    grid_percentile: float = 95.0
    border_percentile: float = 99.0
    border_min_score: float = 0.5
    place_percentile: float = 95.0
    hd_percentile: float = 99.0
    speed_percentile: float = 99.0
    conjunctive_percentile: float = 99.0
    spatial_gate: bool = True
    factorial_gate: bool = True
    threshold: str = "unit"
    precedence: tuple = ("conjunctive", "grid", "border", "place", "head_direction",
                         "speed")

@dataclass(frozen=True)
class IntrinsicDimensionConfig:
    """Defaults of :func:`intrinsic_dimension` (scikit-dimension's nearest-neighbour
    estimators beside Grassberger-Procaccia).

    Attributes
    ----------
    estimators : tuple of str
        TwoNN (Facco et al. 2017: the ratio of second to first neighbour distances) and
        MLE (Levina & Bickel 2005: the likelihood of the first ``k`` neighbour
        distances): two estimators with no scaling range to choose, unlike C(r).
    n_neighbors : int
        MLE uses the 20 nearest neighbours, the top of Levina & Bickel's suggested 10-20.
    twonn_discard : float
        TwoNN drops the 10% largest ratios before its fit (Facco et al. 2017).
    max_points, theiler, transient, seed
        As for :class:`CorrelationDimensionConfig`, so that both see the same states:
        neighbours closer in time than ``theiler`` samples within a trial are skipped
        (otherwise the nearest neighbour of a state on a smooth trajectory is its own
        near past, and the estimate is that of a curve, ~1).
    """

    estimators: tuple = ("TwoNN", "MLE")
    n_neighbors: int = 20
    twonn_discard: float = 0.1
    max_points: int = 4000
    theiler: int = 10
    transient: float = 0.1
    seed: int = 0


@dataclass(frozen=True)
class ScorecardConfig:
    """Rules of :func:`~hippo_probe.analysis.map_scorecard.map_scorecard`, fixed before any
    model variant was trained (the map-ingredient study must not fit its rules to its
    numbers).

    Attributes
    ----------
    max_fields : int
        A place-like unit has 1 to 3 fields (CA1 place cells in a small box: mostly one,
        rarely more than three; Park, Dvorak & Fenton 2011).
    max_field_fraction : float
        ... covering at most half of the visited area together: a smooth gradient's map
        thresholded at a fraction of its peak leaves one "field" over most of the arena.
    place_fraction : float
        Verdict "place fields": at least 30% of the units are place-like (a CA1 session
        has a third or more of its active pyramidal cells with fields in a given box).
    global_across, global_within : float
        Verdict "global remapping": the median unit's maps correlate below 0.3 across
        environments while above 0.7 within one (split halves): maps that are stable yet
        unrelated between arenas (Leutgeb et al. 2005).
    silent_fraction : float
        A unit is silent in an environment when its peak rate is below 10% of the
        population's median peak there.
    min_bins : int
        Bins visited in both environments below which a map correlation is NaN (5).
    """

    max_fields: int = 3
    max_field_fraction: float = 0.5
    place_fraction: float = 0.3
    global_across: float = 0.3
    global_within: float = 0.7
    silent_fraction: float = 0.1
    min_bins: int = 5


CONVENTIONS = RecordingConventions()
SCORECARD = ScorecardConfig()
COMPUTE = ComputeConfig()
RATEMAP = RateMapConfig()
SHUFFLE = ShuffleConfig()
INFORMATION = InformationConfig()
HEAD_DIRECTION = HeadDirectionConfig()
STABILITY = StabilityConfig()
REMAPPING = RemappingConfig()
DECODING = DecodingConfig()
CORRELATION_DIMENSION = CorrelationDimensionConfig()
ENVIRONMENT_DECODING = EnvironmentDecodingConfig()
INTRINSIC_DIMENSION = IntrinsicDimensionConfig()
PLACE_FIELD = PlaceFieldConfig()
GRID = GridConfig()
BORDER = BorderConfig()
SPEED = SpeedConfig()
CONJUNCTIVE = ConjunctiveConfig()
CELL_CLASS = CellClassConfig()
