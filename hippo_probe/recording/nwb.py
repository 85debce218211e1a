"""NWB import (``from_nwb``) and export (``to_nwb``); pynwb is imported when called.

NWB (Neurodata Without Borders, Rübel et al. 2022, eLife 11:e78362) is the community
format for rodent electrophysiology. The import maps an NWB session onto the recording
schema: tracking samples become ``time``, ``Units`` spike times are binned onto them,
epochs and trials become the trial table, ``Units`` columns become unit coords.
"""

from __future__ import annotations

import datetime
import json
import os
import uuid
import warnings

import numpy as np

from .._atomic import atomic_path
from .._validators import check_bool, check_option, check_path
from ..errors import RecordingError
from .._angles import wrap_angle
from .arrays import LENGTH_UNITS, bin_spikes, check_time, degrees_wrap, warn_large_floor
from .config import DEFAULTS
from .layout import assemble, trial_blocks
from .schema import annotate
from .validate import check_text_variables, json_ready, validate

#: NWB ``unit`` strings of lengths -> the keys of :data:`LENGTH_UNITS`.
NWB_LENGTH_UNITS = {
    "m": "m", "meter": "m", "meters": "m", "metre": "m", "metres": "m",
    "cm": "cm", "centimeter": "cm", "centimeters": "cm", "centimetre": "cm",
    "centimetres": "cm", "mm": "mm", "millimeter": "mm", "millimeters": "mm",
    "millimetre": "mm", "millimetres": "mm",
}
#: Radians per unit of the NWB angle units understood.
NWB_ANGLE_UNITS = {"radian": 1.0, "radians": 1.0, "rad": 1.0, "degree": np.pi / 180,
                   "degrees": np.pi / 180, "deg": np.pi / 180}
#: Units-table columns that are not per-unit labels.
_NOT_UNIT_COORDS = {"spike_times", "obs_intervals", "electrodes", "waveform_mean",
                    "waveform_sd", "waveforms"}
#: NWB processing module where ``to_nwb`` puts what has no standard NWB type.
MODULE = "hippo_probe"
#: Intervals table of the tracked time support (pynapple's name for it).
SUPPORT = "position_time_support"
_ATTRS_NOTE = "hippo_probe recording attrs: "
#: Ends the description of a unit-table column that holds bools as uint8.
BOOL_NOTE = " (bool, as uint8)"


def _nwb_classes():
    try:
        import pynwb
        from pynwb.behavior import CompassDirection, Position, SpatialSeries
    except ImportError as err:   # pragma: no cover - pynwb is a declared extra
        raise ImportError("NWB import/export needs pynwb: pip install 'hippo_probe[nwb]'") \
            from err
    return pynwb, Position, CompassDirection, SpatialSeries


def _containers(nwb, cls):
    """(location, object) of every ``cls`` under processing modules and acquisition."""
    found = []
    for mod_name, module in nwb.processing.items():
        found += [(f"processing/{mod_name}/{k}", v) for k, v in module.data_interfaces.items()
                  if isinstance(v, cls)]
    found += [(f"acquisition/{k}", v) for k, v in nwb.acquisition.items() if isinstance(v, cls)]
    return found


def _pick(found, name, what, path):
    if not found:
        raise RecordingError(f"`path` has no {what} (looked in processing/* and "
                             f"acquisition): {path}")
    if name is None:
        return found[0]
    for location, obj in found:
        if name in (location, location.rsplit("/", 1)[-1]):
            return location, obj
    raise RecordingError(f"`{what.split()[0].lower()}` must name one of "
                         f"{[loc for loc, _ in found]}; got {name!r}")


#: Plausibility rule for imported values (a garbled HDF5 block reads as numbers like
#: 6e206): positions within 1 km of the origin (no lab arena comes close) and times
#: (tracking timestamps, spike times) within 1e7 s (116 days) of the session start,
#: angles within 1e6 rad. Anything beyond is refused, named.
MAX_POSITION_M = 1e3
MAX_TIME_S = 1e7
MAX_ANGLE_RAD = 1e6      # unwrapped angles may hold many turns; not 1e6 radians of them
#: Share of all spike times beyond the end of everything the file times (tracking,
#: epochs, trials) above which the spike times are warned to be on another clock or in
#: another unit (milliseconds keep a few of the first spikes of a session inside it).
BEYOND_SESSION_WARNING = 0.5


def _check_plausible(name, values, limit, unit, path):
    values = np.asarray(values, dtype=float)
    bad = np.abs(values) > limit
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        raise RecordingError(
            f"`{name}` in {path} holds {int(bad.sum())} values beyond {limit:g} {unit} "
            f"(first {float(values[idx]):g} at index {idx if len(idx) > 1 else idx[0]}): not a "
            f"plausible {name}; the file may be damaged or its units wrong")
    return values


def _read(dataset, what):
    """``dataset[:]`` once its declared size is known to be bounded
    (:attr:`RecordingConfig.max_read_bytes`): a header can declare any shape."""
    _check_size(dataset, what)
    return dataset[:]


def _check_size(dataset, what):
    shape = getattr(dataset, "shape", None)
    dtype = getattr(dataset, "dtype", None)
    if shape is not None:
        itemsize = getattr(dtype, "itemsize", 8) or 8
        n_bytes = float(np.prod([float(s) for s in shape])) * itemsize
        if n_bytes > DEFAULTS.max_read_bytes:
            raise RecordingError(f"{what} declares shape {tuple(shape)} ({n_bytes / 2**30:.3g}"
                                 f" GiB), more than the {DEFAULTS.max_read_bytes / 2**30:g} GiB "
                                 f"read from a file at once: refused (a damaged or crafted "
                                 f"file?)")


def _refuse_external_links(path):
    """An NWB (HDF5) file may link to datasets in other files: reading it would read
    them, wherever they are. Only the file given is read."""
    import h5py

    found = []

    def visit(name, link):
        if isinstance(link, h5py.ExternalLink):
            found.append(f"{name} -> {link.filename}:{link.path}")

    try:
        with h5py.File(path, "r") as f:
            f.visititems_links(visit)
    except (OSError, RuntimeError) as err:    # h5py: RuntimeError for damaged headers
        raise RecordingError(f"`path` is not a readable NWB file: {path} "
                             f"({type(err).__name__}: {err})") from err
    if found:
        raise RecordingError(f"`path` {path} links to data in other files ({found[0]}"
                             f"{' and more' if len(found) > 1 else ''}): refused; only the "
                             f"file given is read")


def _raised_in_h5py(err) -> bool:
    """Whether ``err`` was raised inside h5py (a read of the file), not by other code."""
    import traceback

    frames = traceback.extract_tb(err.__traceback__)
    # h5py's compiled modules report themselves as "h5py/....pyx"
    return bool(frames) and "h5py" in frames[-1].filename.replace(os.sep, "/").split("/")


def _timestamps(series):
    if series.timestamps is not None:
        return np.asarray(_read(series.timestamps, f"`{series.name}.timestamps`"),
                          dtype=float)
    n = series.data.shape[0]
    return series.starting_time + np.arange(n) / series.rate


def _values(series):
    """Series data in its file units times ``conversion`` plus ``offset``."""
    data = np.asarray(_read(series.data, f"`{series.name}.data`"), dtype=float)
    conversion = series.conversion
    if not (np.isfinite(conversion) and conversion != 0):
        raise RecordingError(f"`{series.name}.conversion` must be a finite non-zero factor "
                             f"to the series' unit; got {conversion!r} (every value would "
                             f"become {0 if conversion == 0 else conversion})")
    return data * conversion + getattr(series, "offset", 0.0)


def _axes_table(series_by_name):
    """Axis name -> (series, column): 1-D series by name; the columns of a lone 2-D series
    as "x", "y", "z"; columns of several 2-D series as "name[j]"."""
    table = {}
    alone = len(series_by_name) == 1
    for name, series in series_by_name.items():
        if series.data.ndim == 1:
            table[name] = (series, None)
            continue
        for j in range(series.data.shape[1]):
            if alone:
                label = "xyz"[j] if series.data.shape[1] <= 3 else str(j)
            else:
                label = f"{name}[{j}]"
            table[label] = (series, j)
    return table


def _column(entry):
    series, j = entry
    values = _values(series)
    return values if j is None else values[:, j]


def _is_angle(series) -> bool:
    """Whether a series declares an angle unit (a head direction, not a position)."""
    return str(series.unit).strip().lower() in NWB_ANGLE_UNITS


def _default_floor_axes(axes, columns, location):
    """The two floor axes when none are named: the two of largest spread (the vertical
    axis of a floor-bound animal barely moves), both from one series when the container
    holds 2-D series (two LEDs' x would otherwise pair with each other), never a series
    in an angle unit."""
    candidates = [a for a, (series, _) in axes.items() if not _is_angle(series)]
    wide = list(dict.fromkeys(series.name for series, j in axes.values()
                              if j is not None and not _is_angle(series)))
    if len(wide) > 1:
        first = [a for a in candidates if axes[a][0].name == wide[0]]
        raise RecordingError(
            f"the position container {location} holds several 2-D series {wide}: which "
            f"one is the animal's position is not known; pass floor_axes naming two "
            f"columns of one, e.g. floor_axes={tuple(first[:2])!r} (`--floor-axes` of "
            f"`hippo-probe import-nwb`)")
    if wide:
        candidates = [a for a in candidates if axes[a][0].name == wide[0]]
    if len(candidates) < 2:
        raise RecordingError(f"the position container {location} has fewer than two axes "
                             f"of length ({list(axes)}; those in an angle unit are head "
                             f"directions); pass floor_axes")
    spread = {axis: np.nanstd(columns[axis]) for axis in candidates}
    return tuple(sorted(sorted(spread, key=spread.get)[-2:], key=list(axes).index))


def _read_position(nwb, name, floor_axes, position_units, path):
    _, Position, _, SpatialSeries = _nwb_classes()
    found = _containers(nwb, Position) + _containers(nwb, SpatialSeries)
    if name is None:     # a bare series in an angle unit is a head direction
        found = [(loc, obj) for loc, obj in found
                 if not (isinstance(obj, SpatialSeries) and _is_angle(obj))] or found
    location, container = _pick(found, name, "Position (SpatialSeries) data", path)
    axes = _axes_table({container.name: container} if isinstance(container, SpatialSeries)
                       else container.spatial_series)
    columns = {axis: _column(entry) for axis, entry in axes.items()}
    # an axis without one finite value is damage (erased storage reads as NaN), not an
    # axis that barely moves: chosen by spread, its neighbours would take its place
    empty = [axis for axis, v in columns.items() if not np.isfinite(v).any()]
    if empty and (floor_axes is None or set(empty) & set(floor_axes)):
        others = [a for a in axes if a not in empty]
        hint = (f"; if it was never tracked, pass floor_axes={tuple(others[:2])!r} (or two "
                f"other axes of {others})" if len(others) >= 2 else "")
        raise RecordingError(f"position axis {empty[0]!r} in {path} ({location}) has no "
                             f"finite value: the file is damaged, or the axis was not "
                             f"tracked{hint}")
    if floor_axes is None:
        floor_axes = _default_floor_axes(axes, columns, location)
    floor_axes = tuple(floor_axes)
    for axis in floor_axes:
        check_option("floor_axes", axis, list(axes))
    if len(floor_axes) != 2 or floor_axes[0] == floor_axes[1]:
        raise ValueError(f"`floor_axes` must name two different axes of {list(axes)}; "
                         f"got {floor_axes!r}")
    first = axes[floor_axes[0]][0]
    time = _timestamps(first)
    for axis in floor_axes:
        if axes[axis][0] is not first and not np.array_equal(_timestamps(axes[axis][0]), time):
            raise RecordingError(f"position axes {floor_axes} have different timestamps in "
                                 f"{location}")
    declared = str(first.unit).strip().lower()
    unit = position_units or NWB_LENGTH_UNITS.get(declared)
    if unit is None:
        if declared not in ("", "unknown", "none", "n/a", "a.u."):
            raise RecordingError(f"position unit {first.unit!r} in {path} is not a length "
                                 f"this reader knows ({sorted(NWB_LENGTH_UNITS)}); pass "
                                 f"`position_units` ('m', 'cm' or 'mm'; `--position-units` "
                                 f"of `hippo-probe import-nwb`) if you know it")
        warnings.warn(f"the position in {path} has no unit ({first.unit!r}): taken as "
                      f"metres; pass `position_units` (`--position-units` of "
                      f"`hippo-probe import-nwb`) if it is not", UserWarning,
                      stacklevel=4)
        unit = "m"
    xy = np.column_stack([columns[a] for a in floor_axes]) * LENGTH_UNITS[
        check_option("position_units", unit, LENGTH_UNITS)]
    _check_plausible("position", xy, MAX_POSITION_M, "m", path)
    if not np.isfinite(xy).any():
        raise RecordingError(f"`position` in {path} ({location}) is all NaN: no tracked "
                             f"sample to analyse")
    # pynwb's SpatialSeries unit defaults to "meters", often left so for centimetres
    warn_large_floor(xy, f"its unit in {path}: {first.unit!r}, read as {unit}",
                     "pass position_units='cm' (`--position-units cm` of "
                     "`hippo-probe import-nwb`)", stacklevel=4)
    _check_plausible("position timestamps", time, MAX_TIME_S, "s", path)
    return time, xy, {"nwb_position": location, "nwb_floor_axes": list(floor_axes),
                      "nwb_position_units": unit}


def _read_head_direction(nwb, name, floor_axes, sign, units, time, path):
    _, Position, CompassDirection, SpatialSeries = _nwb_classes()
    found = _containers(nwb, CompassDirection)
    if not found and name is None:
        angles = [loc for loc, obj in _containers(nwb, SpatialSeries) if _is_angle(obj)]
        angles += [f"{loc}/{k}" for loc, obj in _containers(nwb, Position)
                   for k, series in obj.spatial_series.items() if _is_angle(series)]
        if angles:      # said, as a lab that stored it so would otherwise not notice
            verb = "was" if len(angles) == 1 else "were"
            warnings.warn(f"{path} has no CompassDirection, so no head direction is "
                          f"imported; the series {angles}, in an angle unit, {verb} not "
                          f"taken as one (NWB keeps head direction in a CompassDirection)",
                          UserWarning, stacklevel=4)
        return None, {}
    location, container = _pick(found, name if name is None or "/" in name else None,
                                "CompassDirection data", path)
    axes = _axes_table(container.spatial_series)
    vertical = [a for a in "xyz" if a not in floor_axes]
    if name is not None and "/" not in name:
        key = name
    elif len(axes) == 1:
        key = next(iter(axes))
    elif len(vertical) == 1 and f"r{vertical[0]}" in axes:
        key = f"r{vertical[0]}"       # rotation about the vertical axis
    else:
        raise RecordingError(f"`head_direction` must name one of {list(axes)} in {location} "
                             "(cannot tell which is the rotation about the vertical)")
    check_option("head_direction", key, list(axes))
    series = axes[key][0]
    declared = str(series.unit).strip().lower()
    if units is not None:
        declared = check_option("head_direction_units", units, ("rad", "deg"))
    scale = NWB_ANGLE_UNITS.get(declared)
    if scale is None:
        # taken as radians, said aloud: degrees read as radians would pass the
        # plausibility check below (unwrapped angles may span many turns)
        warnings.warn(f"the head direction in {path} has "
                      + (f"no unit ({series.unit!r})" if declared in
                         ("", "unknown", "none", "n/a", "a.u.")
                         else f"the unit {series.unit!r}, not an angle this reader knows "
                              f"({sorted(NWB_ANGLE_UNITS)})")
                      + ": taken as radians", UserWarning, stacklevel=4)
        scale = 1.0
    if sign == "auto":
        # Right-handed rotation about the vertical c turns the floor axis a toward b when
        # (a, b, c) is a cyclic order of (x, y, z); otherwise the counter-clockwise angle
        # in the (a, b) floor is the negative of the stored rotation.
        order = "".join(floor_axes) + "".join(vertical)
        sign = 1 if len(order) != 3 or order in ("xyz", "yzx", "zxy") else -1
    check_option("head_direction_sign", sign, (1, -1))
    stored = _column(axes[key])
    wraps = degrees_wrap(stored) if scale == 1.0 else None
    if wraps is not None:
        raise RecordingError(
            f"the head direction in {path} ({location}/{key}) is read as radians (its unit: "
            f"{series.unit!r}) but jumps by {abs(stored[wraps + 1] - stored[wraps]):.0f} "
            f"between samples {wraps} and {wraps + 1} (from {stored[wraps]:.4g} to "
            f"{stored[wraps + 1]:.4g}), as degrees wrapping at 360 do: it is in degrees; "
            f"pass head_direction_units='deg' (`--head-direction-units deg` of "
            f"`hippo-probe import-nwb`)")
    angle = _check_plausible("head_direction", stored * scale * sign, MAX_ANGLE_RAD, "rad",
                             path)
    hd_time = _check_plausible("head_direction timestamps", _timestamps(series), MAX_TIME_S,
                               "s", path)
    if hd_time.size != time.size or not np.allclose(hd_time, time, atol=1e-9, rtol=0):
        # different clock: interpolate the unit vector, so wrap-around is handled
        angle = np.arctan2(np.interp(time, hd_time, np.sin(angle), left=np.nan, right=np.nan),
                           np.interp(time, hd_time, np.cos(angle), left=np.nan, right=np.nan))
    return wrap_angle(angle), {"nwb_head_direction": f"{location}/{key}",
                               "nwb_head_direction_sign": int(sign)}


def _intervals(table):
    """(ids, starts, stops) of the rows of an NWB TimeIntervals table."""
    if table is None or len(table) == 0:
        return None
    return (np.asarray(table.id[:]), np.asarray(table["start_time"][:], dtype=float),
            np.asarray(table["stop_time"][:], dtype=float))


def _epoch_rows(nwb, epoch, path):
    if epoch is None:
        return None
    table = nwb.epochs
    names = []
    if table is not None and len(table):
        if "tags" in table.colnames:
            names = [list(map(str, tags)) for tags in table["tags"][:]]
        else:
            names = [[str(i)] for i in table.id[:]]
    if not names:
        raise RecordingError(f"`epoch` {epoch!r} cannot be found: the file has no epochs "
                             "table; pass epoch=None (CLI: --epoch all) to import all the "
                             "tracked time")
    keep = np.array([epoch in tags for tags in names], dtype=bool)
    if not keep.any():
        known = sorted({t for tags in names for t in tags})
        raise RecordingError(f"`epoch` must be one of the epochs of the file {known}; got "
                             f"{epoch!r}")
    ids, starts, stops = _intervals(table)
    return ids[keep], starts[keep], stops[keep]


def _trial_intervals(nwb, epoch_rows, trials, support):
    """Trial ids and intervals: NWB trials inside the epoch(s), or the epochs themselves."""
    use_trials = trials is True or (trials == "auto" and nwb.trials is not None
                                    and len(nwb.trials) > 0)
    if use_trials:
        if nwb.trials is None or len(nwb.trials) == 0:
            raise RecordingError("`trials` is True but the file has no trials table")
        ids, starts, stops = _intervals(nwb.trials)
        if epoch_rows is not None:
            inside = np.zeros(ids.size, dtype=bool)
            for a, b in zip(epoch_rows[1], epoch_rows[2]):
                inside |= (starts >= a) & (stops <= b)
            ids, starts, stops = ids[inside], starts[inside], stops[inside]
    elif epoch_rows is not None:
        ids, starts, stops = epoch_rows
    else:
        ids, starts, stops = np.array([0]), support[0][:1], support[1][-1:]
    starts, stops = _clip_to_support(starts, stops, *support)
    order = np.argsort(starts, kind="stable")
    ids, starts, stops = ids[order], starts[order], stops[order]
    keep = stops >= starts
    return ids[keep], starts[keep], stops[keep], use_trials


def _support(nwb, time):
    """Intervals where tracking is defined: the file's ``position_time_support`` table
    (pynapple's convention, also written by :func:`to_nwb`) or [first, last sample]."""
    table = nwb.intervals.get(SUPPORT) if nwb.intervals else None
    rows = _intervals(table)
    if rows is None:
        return np.array([time[0]]), np.array([time[-1]])
    order = np.argsort(rows[1])
    return rows[1][order], rows[2][order]


def _clip_to_support(starts, stops, support_starts, support_stops):
    """Shrink each interval to the hull of its overlap with the support intervals."""
    first = np.searchsorted(support_stops, starts, side="left")     # first support ending >= start
    last = np.searchsorted(support_starts, stops, side="right") - 1  # last support starting <= stop
    valid = (first < support_starts.size) & (last >= 0) & (first <= last)
    first, last = first.clip(0, support_starts.size - 1), last.clip(0, support_starts.size - 1)
    new_starts = np.where(valid, np.maximum(starts, support_starts[first]), np.inf)
    new_stops = np.where(valid, np.minimum(stops, support_stops[last]), -np.inf)
    return new_starts, new_stops


def _assign_samples(time, ids, starts, stops, dt, config):
    """Trial of each sample (-1 outside every trial), leaving the schema's gap between
    trials that touch (the first samples of the later trial are left out)."""
    trial = np.full(time.size, -1, dtype=np.int64)
    for k in range(ids.size):
        lo, hi = np.searchsorted(time, [starts[k], stops[k]], side="left")
        hi = np.searchsorted(time, stops[k], side="right")
        inside = np.arange(lo, hi)
        inside = inside[trial[inside] == -1]
        trial[inside] = k
    for k in range(1, ids.size):
        prev = np.flatnonzero(trial == k - 1)
        if prev.size == 0:
            continue
        mine = np.flatnonzero(trial == k)
        too_close = mine[time[mine] - time[prev[-1]] < 2 * dt * (1 - config.gap_jitter)]
        trial[too_close] = -1
    return trial


def from_nwb(path, epoch="wake", *, trials="auto", floor_axes=None, head_direction=None,
             head_direction_sign="auto", position=None, position_units=None,
             head_direction_units=None, environment=0, activity="auto", units=None,
             config=DEFAULTS):
    """Import an NWB session as a recording (needs pynwb).

    Position comes from a ``Position`` (or ``SpatialSeries``) under ``processing/*`` or
    ``acquisition``, scaled by its ``conversion`` (and ``offset``) and converted to
    metres; two of its axes form the floor plane. Head direction comes from a
    ``CompassDirection`` (by default the rotation about the vertical axis), with a sign
    chosen so that it is counter-clockwise from the first floor axis toward the second.
    Spike times of the ``Units`` table are binned onto the tracking samples
    (:func:`~hippo_probe.recording.bin_spikes`: nearest sample within a trial's interval,
    no further than about half a sample interval from it), so the counts add up to the
    spikes inside the trials, except those where the tracking skipped frames or paused,
    which are left out and warned about. Trials are the rows of the
    file's trials table inside the epoch, or else the epoch's rows, intersected with the
    tracked time support ``[first, last tracking sample]``. ``Units`` columns (e.g.
    ``location``, renamed ``region``) become unit coords.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.nwb`` file.
    epoch : str or None
        Tag (``epochs`` table, column ``tags``) of the epoch(s) to import, e.g.
        ``"wake"``; ``None`` imports the whole tracked time.
    trials : "auto", bool
        Split the epoch by the file's trials table (``"auto"``: when there is one).
        Where two trials touch, the first samples of the later one are left out so that
        trials are separated by one ``dt`` (the schema's gap); their spikes are not
        counted, as their positions are not kept.
    floor_axes : pair of str, optional
        Axes forming the floor, mapped to the recording's (x, y): names of 1-D series of
        the Position container (``("x", "z")``), or ``"x"``, ``"y"``, ``"z"`` for the
        columns of a single 2-D series (``"name[0]"``, ``"name[1]"`` for the columns of
        one of several). Default: the two axes with the largest spread (the vertical axis
        of a floor-bound animal barely moves), both from the container's 2-D series if it
        has one (refused if it has several, e.g. two LEDs: name the columns), never from
        a series in an angle unit.
    head_direction : str, optional
        Name of the CompassDirection series (or axis) to use; default: the only one, or
        ``"r" + vertical axis`` (e.g. ``"ry"`` when the floor is (x, z)).
    head_direction_sign : "auto", 1 or -1
        ``-1`` negates the stored angle. ``"auto"``: ``+1`` when (floor axes, vertical)
        is a right-handed (cyclic) order of x, y, z, else ``-1`` (a right-handed rotation
        about y turns z toward x, i.e. clockwise in the (x, z) floor).
    position : str, optional
        Name or location of the Position container (default: the first found).
    position_units : {"m", "cm", "mm"}, optional
        Override the series' ``unit`` (used when the field is empty or wrong; an empty
        field is read as metres).
    head_direction_units : {"rad", "deg"}, optional
        Override the head direction's ``unit`` (used when the field is empty or wrong; an
        empty field is read as radians, with a warning). An angle read as radians that
        wraps at 360 is refused: degrees, whatever the file says.
    environment : int or str
        Environment id of every trial, or the name of an integer column of the trials
        table.
    activity : "auto", "units" or "series"
        Where activity comes from: the ``Units`` table (spike counts) or the
        ``processing/hippo_probe/activity`` TimeSeries that :func:`to_nwb` writes
        (``"auto"``: the series when present).
    config : RecordingConfig
        Validation tolerances (gap between touching trials).

    Returns
    -------
    xarray.Dataset
        A valid recording, ``source="animal"`` (unless the file says otherwise).

    Raises
    ------
    RecordingError
        Not an NWB file; no position; an unknown epoch; no tracking samples in the epoch;
        several 2-D position series and no ``floor_axes``; a head direction read as
        radians that wraps at 360 (degrees); units observed for only part of the
        imported time (``obs_intervals``) and not left out by ``units``.

    Warns
    -----
    UserWarning
        Spikes that fall where the tracking paused; a tracked floor wider than 20 m
        (centimetres under pynwb's default unit "meters"?); most spike times after the
        end of everything else the file times (milliseconds?); angle series that are not
        in a ``CompassDirection`` (not imported as head direction); a position or head
        direction without a unit.

    Examples
    --------
    >>> rec = from_nwb("tests/data/A2929-200711.nwb", epoch="wake")   # doctest: +SKIP
    >>> rec.sizes["unit"], str(rec.region.values[0])                  # doctest: +SKIP
    (15, 'adn')
    """
    pynwb = _nwb_classes()[0]
    path = check_path("path", path)
    if path.is_dir():
        raise IsADirectoryError(f"`path` must be an NWB file; got the directory {path}")
    if not path.is_file():
        raise FileNotFoundError(f"`path` does not exist: {path}")
    check_option("trials", trials, ("auto", True, False))
    check_option("activity", activity, ("auto", "units", "series"))
    _refuse_external_links(path)
    try:
        io = pynwb.NWBHDF5IO(str(path), "r")
        with warnings.catch_warnings():
            # deprecations in how an older file was written are not the reader's to fix
            warnings.simplefilter("ignore", DeprecationWarning)
            nwb = io.read()
    except Exception as err:
        raise RecordingError(f"`path` is not a readable NWB file: {path} "
                             f"({type(err).__name__}: {err})") from err
    with io:
        try:
            return _from_nwb(nwb, path, epoch, trials, floor_axes, head_direction,
                             head_direction_sign, head_direction_units, position,
                             position_units, environment, activity, units, config)
        except (OSError, RuntimeError) as err:
            # h5py reads lazily: a damaged dataset surfaces here, as h5py's own errors
            if not _raised_in_h5py(err):
                raise
            raise RecordingError(f"`path` is a damaged NWB file: {path} "
                                 f"({type(err).__name__}: {err})") from err


def _from_nwb(nwb, path, epoch, trials, floor_axes, head_direction, head_direction_sign,
              head_direction_units, position, position_units, environment, activity, units,
              config):
    epoch_rows = _epoch_rows(nwb, epoch, path)
    time, xy, attrs = _read_position(nwb, position, floor_axes, position_units, path)
    time = check_time(time, "position timestamps")
    hd, hd_attrs = _read_head_direction(nwb, head_direction, attrs["nwb_floor_axes"],
                                        head_direction_sign, head_direction_units, time,
                                        path)
    attrs.update(hd_attrs)
    ids, starts, stops, from_trials = _trial_intervals(nwb, epoch_rows, trials,
                                                       _support(nwb, time))
    dt = float(np.median(np.diff(time)))
    session_end = _session_end(nwb, time)
    index = _assign_samples(time, ids, starts, stops, dt, config)
    keep = index >= 0
    if not keep.any():
        raise RecordingError(f"`epoch` {epoch!r} holds no tracking samples (tracking covers "
                             f"{time[0]:.3f}-{time[-1]:.3f} s) in {path}")
    present = np.unique(index[keep])
    ids, starts, stops = ids[present], starts[present], stops[present]
    index = np.searchsorted(present, index[keep])
    time, xy = time[keep], xy[keep]
    sample_starts, sample_stops, _ = trial_blocks(index)
    # the sample interval of the samples kept (an epoch may be tracked at another rate
    # than the rest of the file), within trials, as the schema's dt means
    within = np.diff(time)[index[1:] == index[:-1]]
    if within.size:
        dt = float(np.median(within))
    trial_env = _trial_environment(nwb, environment, ids, from_trials)

    values, unit_ids, unit_coords, kind = _read_activity(
        nwb, activity, keep, time, index, starts, stops, units, session_end, path)
    # a file written by to_nwb carries the recording's own attrs: restore them exactly
    attrs = _saved_attrs(nwb) or {
        "source": "animal", "activity_kind": kind,
        "session_id": str(nwb.session_id or nwb.identifier),
        "subject": str(getattr(nwb.subject, "subject_id", "") or ""),
        "species": str(getattr(nwb.subject, "species", "") or ""),
        "nwb_file": path.name, "epoch": "" if epoch is None else str(epoch),
        "session_start_time": nwb.session_start_time.isoformat(), **attrs}
    extras = _read_extras(nwb, keep)
    env_ids = extras.pop("environment_id", None)
    rec = assemble(time=time, trial=ids[index], trial_id=ids,
                   trial_time=time - np.repeat(starts, sample_stops - sample_starts),
                   table={"trial_start": starts, "trial_stop": stops,
                          "trial_environment": trial_env}, dt=dt, attrs=attrs,
                   environment_ids=None if env_ids is None else env_ids[1])
    if env_ids is not None:
        rec.variables["environment_id"].attrs.update(env_ids[2])
    rec = rec.assign_coords(unit=unit_ids)
    rec = rec.assign_coords({k: ("unit", v) for k, v in unit_coords.items()})
    for name in unit_coords:
        rec.variables[name].attrs.update(units="", long_name=name.replace("_", " "))
    rec["activity"] = ("time", "unit"), values
    rec["position"] = ("time", "space"), xy
    if hd is not None:
        rec["head_direction"] = "time", hd[keep]
    for name, (dims, data, var_attrs, is_coord) in sorted(extras.items(),
                                                          key=lambda kv: not kv[1][3]):
        if is_coord:
            rec = rec.assign_coords({name: (dims, data, var_attrs)})
        else:
            rec[name] = dims, data, var_attrs
    for name, var_attrs in _saved_var_attrs(nwb).items():
        if name in rec.variables:
            rec.variables[name].attrs.update(var_attrs)
    return validate(annotate(rec))


def _trial_environment(nwb, environment, ids, from_trials):
    if isinstance(environment, str):
        if not from_trials or environment not in nwb.trials.colnames:
            cols = list(nwb.trials.colnames) if nwb.trials is not None else []
            raise RecordingError(f"`environment` must be an integer or a column of the "
                                 f"trials table {cols}; got {environment!r}")
        table_ids = np.asarray(nwb.trials.id[:])
        column = np.asarray(nwb.trials[environment][:])
        if column.dtype.kind not in "iu":
            raise RecordingError(f"`environment` column {environment!r} must hold integers; "
                                 f"got dtype {column.dtype}")
        # the row of each trial id (ids need not be sorted in the table)
        order = np.argsort(table_ids, kind="stable")
        rows = order[np.searchsorted(table_ids, ids, sorter=order).clip(0, table_ids.size - 1)]
        return column[rows]
    if from_trials and environment == 0 and nwb.trials is not None \
            and "environment" in nwb.trials.colnames:
        return _trial_environment(nwb, "environment", ids, from_trials)
    return np.full(ids.size, int(environment))


def _read_activity(nwb, activity, keep, time, index, starts, stops, chosen, session_end,
                   path):
    module = nwb.processing.get(MODULE)
    series = module.data_interfaces.get("activity") if module is not None else None
    if activity == "series" or (activity == "auto" and series is not None):
        if series is None:
            raise RecordingError(f"`activity` is 'series' but the file has no "
                                 f"processing/{MODULE}/activity")
        if chosen is not None:
            raise ValueError("`units` selects rows of the Units table; this file's "
                             "activity is a series (pass activity='units' to read spikes)")
        values = np.asarray(_read(series.data, f"`{series.name}.data`"))[keep].astype(
            np.float32)
        table = module.data_interfaces.get("unit_table")
        coords = {} if table is None else {
            c: _text(table[c][:]).astype(bool) if table[c].description.endswith(BOOL_NOTE)
            else _text(table[c][:]) for c in table.colnames if c != "unit"}
        ids = (np.arange(values.shape[1]) if table is None else _text(table["unit"][:]))
        kind = _saved_attrs(nwb).get("activity_kind", "rate")
        return values, ids, coords, kind
    units = nwb.units
    if units is None or len(units) == 0:
        raise RecordingError("the NWB file has no Units table (spike times) and no "
                             f"processing/{MODULE}/activity series")
    _check_size(units["spike_times"].target.data, "the Units table's `spike_times`")
    # each unit's spikes are the slice between consecutive index entries: an index that
    # goes back would hand spikes of one unit to another
    ends = np.asarray(_read(units["spike_times"].data, "the Units table's spike index"))
    n_spikes = len(units["spike_times"].target.data)
    if (np.diff(ends.astype(np.int64)) < 0).any() or (ends.size and ends[0] < 0) or (
            ends.size and ends[-1] > n_spikes):
        raise RecordingError(f"the Units table's `spike_times_index` in {path} is not "
                             f"non-decreasing within the spike times: the file is damaged")
    if ends.size and ends[-1] != n_spikes:
        # a ragged column's index ends at its data's end: spikes after it belong to no unit
        raise RecordingError(f"the Units table's `spike_times_index` in {path} ends at "
                             f"{int(ends[-1])} of its {n_spikes} spike times: "
                             f"{n_spikes - int(ends[-1])} spikes belong to no unit; the "
                             f"file is damaged")
    rows = _unit_rows(units, chosen)
    spikes = [np.asarray(units["spike_times"][i], dtype=float) for i in rows]
    negative = sum(int((s < 0).sum()) for s in spikes)
    if negative:
        warnings.warn(f"{negative} spike times in {path} are negative (before the session's "
                      f"start): they fall outside every sample and are dropped",
                      UserWarning, stacklevel=3)
    # a garbled spike time would fall outside every trial and vanish from the counts
    _check_plausible("spike_times", np.concatenate(spikes), MAX_TIME_S, "s", path)
    _warn_spikes_beyond_session(spikes, session_end, path)
    values = bin_spikes(spikes, time, index, starts, stops)
    _refuse_unobserved(units, rows, time, path)
    coords = {}
    for col in units.colnames:
        if col in _NOT_UNIT_COORDS:
            continue
        column = [units[col][i] for i in rows]
        if all(hasattr(v, "name") for v in column):        # e.g. electrode_group
            column = [v.name for v in column]
        column = np.asarray(column)
        if column.ndim == 1 and column.dtype.kind in "iufbUSO":
            coords["region" if col == "location" else col] = _text(column)
    return values, np.asarray(units.id[:])[rows], coords, "spike_count"


def _session_end(nwb, time) -> float:
    """The latest time the file gives to anything but spikes: its tracking, epochs and
    trials."""
    ends = [time[-1]]
    for table in (nwb.epochs, nwb.trials):
        rows = _intervals(table)
        if rows is not None:
            ends.append(float(np.nanmax(rows[2])))
    return float(max(ends))


def _warn_spikes_beyond_session(spikes, end, path):
    """Warn when most spike times come after everything else the file times: spike times
    in milliseconds, or on another clock, would leave a few spikes for a plausible map."""
    every = np.concatenate(spikes) if spikes else np.empty(0)
    beyond = int((every > end).sum())
    if every.size and beyond > BEYOND_SESSION_WARNING * every.size:
        warnings.warn(f"{beyond} of the {every.size} spike times in {path} "
                      f"({beyond / every.size:.0%}) come after the end of everything else "
                      f"the file times ({end:.6g} s: tracking, epochs, trials; the latest "
                      f"spike at {every.max():.6g} s): are the spike times in seconds, on "
                      f"the session's clock? Those outside the trials are not counted",
                      UserWarning, stacklevel=4)


def _unit_rows(units, chosen):
    """Rows of the Units table to import: all, or those of the ids ``chosen``."""
    ids = np.asarray(units.id[:])
    if chosen is None:
        return np.arange(ids.size)
    chosen = np.atleast_1d(np.asarray(chosen))
    missing = [c.item() for c in chosen if c not in ids]
    if missing or chosen.size == 0 or chosen.ndim != 1:
        raise ValueError(f"`units` must be ids of the Units table ({ids.tolist()[:20]}"
                         f"{' ...' if ids.size > 20 else ''}); got "
                         f"{missing or chosen.tolist()}")
    return np.array([int(np.flatnonzero(ids == c)[0]) for c in chosen])


def _refuse_unobserved(units, rows, time, path):
    """Refuse units whose ``obs_intervals`` leave imported samples unobserved: zero
    counts there are not silence. Samples within one sample interval of an interval's
    ends count as observed (the intervals' ends and the tracking clock need not agree)."""
    if "obs_intervals" not in units.colnames or time.size < 2:
        return
    _check_size(units["obs_intervals"].target.data, "the Units table's `obs_intervals`")
    slack = float(np.median(np.diff(time)))
    short = {}
    for i in rows:
        spans = np.asarray(units["obs_intervals"][i], dtype=float).reshape(-1, 2)
        seen = np.zeros(time.size, dtype=bool)
        for a, b in spans:
            seen |= (time >= a - slack) & (time <= b + slack)
        if not seen.all():
            short[int(units.id[i])] = seen.mean()
    if short:
        ids = list(short)
        keep = [int(units.id[i]) for i in rows if int(units.id[i]) not in short]
        shares = ", ".join(f"unit {u}: {v:.0%}" for u, v in list(short.items())[:5])
        raise RecordingError(
            f"units {ids[:10]}{' ...' if len(ids) > 10 else ''} in {path} were observed for "
            f"only part of the imported time (their obs_intervals cover {shares}): their "
            f"spike counts outside would read as silence. Import the others with "
            f"units={keep[:10]}{' ...' if len(keep) > 10 else ''} (`--units` of "
            f"`hippo-probe import-nwb`), or an epoch inside their observed time")


def _text(values):
    values = np.asarray(values)
    return values.astype(str).astype(object) if values.dtype.kind in "USO" else values


def _saved_attrs(nwb):
    """Dataset attrs that :func:`to_nwb` stored in the file's notes."""
    notes = nwb.notes or ""
    if not notes.startswith(_ATTRS_NOTE):
        return {}
    return json.loads(notes[len(_ATTRS_NOTE):])


def _meta(text):
    """The JSON that :func:`to_nwb` keeps in a description, or None."""
    try:
        meta = json.loads(text)
    except (TypeError, ValueError):
        return None
    return meta if isinstance(meta, dict) and "hippo_probe" in meta else None


def _saved_var_attrs(nwb):
    """attrs of variables with a standard NWB home (position, trial table …)."""
    module = nwb.processing.get(MODULE)
    table = module.data_interfaces.get("variable_attrs") if module is not None else None
    if table is None:
        return {}
    return {str(n): json.loads(a) for n, a in zip(table["variable"][:], table["attrs"][:])}


def _read_extras(nwb, keep):
    """Variables that :func:`to_nwb` stored because NWB has no type for them:
    name -> (dims, data, attrs, is_coord)."""
    out = {}
    module = nwb.processing.get(MODULE)
    series = [] if module is None else [
        (name, obj.comments, obj.data) for name, obj in module.data_interfaces.items()
        if name != "activity" and hasattr(obj, "comments")]
    scratch = [(name, obj.description, obj.data) for name, obj in nwb.scratch.items()
               if hasattr(obj, "description")]
    for name, text, data in series + scratch:
        meta = _meta(text)
        if meta is None:
            continue
        values = np.asarray(data[()])
        if meta["dims"][:1] == ["time"]:
            values = values[keep]
        else:    # HDF5 may store a one-element array as a scalar
            values = values.reshape(meta["shape"])
        values = _text(values) if meta["dtype"] in ("object", "str") else values.astype(
            meta["dtype"])
        out[name] = tuple(meta["dims"]), values, meta["attrs"], meta["coord"]
    return out


def to_nwb(rec, path, overwrite=False):
    """Write a recording as an NWB file, so it can be shared in the community format.

    ``position`` becomes a ``Position``/``SpatialSeries`` (metres, the arena frame) and
    ``head_direction`` a ``CompassDirection`` (radians, counter-clockwise from +x), both
    under ``processing/behavior``; the trial table becomes the NWB trials table (column
    ``environment``) and the tracked time support the ``position_time_support`` intervals;
    ``activity`` (LSTM states or binned counts, not spike times) becomes a TimeSeries
    ``processing/hippo_probe/activity`` with the unit coords in a ``unit_table``. The
    other per-sample variables become TimeSeries there too, and the variables NWB has no
    type for (``readout_weight``, ``arena_vertices``, ``environment_id``, …) go to the
    file's ``scratch`` space, each with its dims and attrs as JSON; the dataset attrs are
    kept as JSON in the file's ``notes``. One epoch spans the recording, tagged with its
    ``epoch`` attr (the epoch it was imported from) or else ``"wake"``, so that
    ``from_nwb(path)`` reads it all back with its defaults. The file is written beside
    ``path`` and renamed into place, so a crash leaves no half file.

    Parameters
    ----------
    rec : xarray.Dataset
        A valid recording (loaded into memory while writing).
    path : str or os.PathLike
        Destination ``.nwb`` file.
    overwrite : bool
        Replace an existing file.

    Examples
    --------
    >>> to_nwb(rec, "session.nwb")                      # doctest: +SKIP
    >>> back = from_nwb("session.nwb")                   # doctest: +SKIP
    """
    overwrite = check_bool("overwrite", overwrite)
    pynwb, Position, CompassDirection, SpatialSeries = _nwb_classes()
    from hdmf.common import DynamicTable, VectorData
    from pynwb.epoch import TimeIntervals

    validate(rec)
    check_text_variables(rec, "an NWB file")
    path = check_path("path", path)
    if path.is_dir():
        raise IsADirectoryError(f"`path` must name an .nwb file; got the directory {path}")
    if path.exists() and not overwrite:
        raise FileExistsError(f"`path` already exists: {path}; pass overwrite=True to "
                              "replace it")
    attrs = json_ready(dict(rec.attrs))
    start_time = attrs.get("session_start_time")
    nwb = pynwb.NWBFile(
        session_description=f"hippo_probe recording ({attrs['source']}, "
                            f"{attrs['activity_kind']})",
        identifier=str(attrs.get("session_id") or uuid.uuid4()),
        session_start_time=(datetime.datetime.fromisoformat(start_time) if start_time
                            else datetime.datetime.now(datetime.timezone.utc)),
        notes=_ATTRS_NOTE + json.dumps(attrs))
    time = rec["time"].values
    behavior = nwb.create_processing_module("behavior", "tracking")
    pos = SpatialSeries(name="position", data=rec["position"].values, timestamps=time,
                        unit="meters", reference_frame="arena frame: origin at the arena "
                        "centre, x and y in the floor plane")
    behavior.add(Position(spatial_series=pos, name="Position"))
    if "head_direction" in rec:
        behavior.add(CompassDirection(name="CompassDirection", spatial_series=SpatialSeries(
            name="head_direction", data=rec["head_direction"].values, timestamps=pos,
            unit="radians", reference_frame="counter-clockwise from +x")))
    trial_env = rec["trial_environment"].values
    t_start, t_stop = rec["trial_start"].values, rec["trial_stop"].values
    nwb.add_trial_column("environment", "environment (arena) id of the trial")
    support = TimeIntervals(name=SUPPORT, description="the tracked time support")
    for k, tid in enumerate(rec["trial_id"].values):
        nwb.add_trial(start_time=float(t_start[k]), stop_time=float(t_stop[k]),
                      environment=int(trial_env[k]), id=int(tid))
        support.add_interval(start_time=float(t_start[k]), stop_time=float(t_stop[k]))
    nwb.add_time_intervals(support)
    # one epoch over the whole recording, tagged with the epoch it was imported from, else
    # "wake" (a network's trials are active navigation): from_nwb's default reads it back
    nwb.add_epoch(start_time=float(min(t_start.min(), time[0])),
                  stop_time=float(max(t_stop.max(), time[-1])),
                  tags=[str(attrs.get("epoch") or "wake")])

    module = nwb.create_processing_module(MODULE, "hippo_probe recording variables")
    activity = rec["activity"]
    module.add(pynwb.TimeSeries(name="activity", data=activity.values, timestamps=pos,
                                unit=activity.attrs["units"],
                                description=activity.attrs["long_name"]))
    unit_coords = [c for c, v in rec.coords.items() if v.dims == ("unit",)]
    # HDF5 has no bool: a bool column is written as uint8 and said so in its description
    module.add(DynamicTable(name="unit_table", description="unit ids and unit coords",
                            columns=[VectorData(name=c, description=c + (
                                BOOL_NOTE if rec[c].dtype == bool else ""),
                                data=_nwb_column(rec[c].values)) for c in unit_coords]))
    standard = {"time", "trial", "environment", "trial_id", "trial_start",
                "trial_stop", "trial_environment", "space", "activity", "position",
                "head_direction", *unit_coords}
    names = sorted(standard & set(rec.variables))
    module.add(DynamicTable(
        name="variable_attrs", description="attrs of the recording's variables",
        columns=[VectorData(name="variable", description="variable name", data=names),
                 VectorData(name="attrs", description="attrs as JSON",
                            data=[json.dumps(json_ready(dict(rec[n].attrs))) for n in names])]))
    for name, var in rec.variables.items():
        if name in standard:
            continue
        meta = json.dumps({"hippo_probe": 1, "dims": list(var.dims), "shape": var.shape,
                           "attrs": json_ready(dict(var.attrs)), "coord": name in rec.coords,
                           "dtype": "str" if var.dtype.kind in "UOT" else str(var.dtype)})
        data = _nwb_column(var.values)
        if var.dims[:1] == ("time",):
            module.add(pynwb.TimeSeries(name=name, data=data, timestamps=pos,
                                        unit=var.attrs["units"], comments=meta,
                                        description=var.attrs["long_name"]))
        else:
            nwb.add_scratch(np.asarray(data), name=name, description=meta)
    with atomic_path(path, overwrite=overwrite, what="path") as tmp:
        with pynwb.NWBHDF5IO(str(tmp), "w") as io:
            io.write(nwb)


def _nwb_column(values):
    """Strings as a list of str (HDF5 variable-length strings); bools as uint8."""
    if values.dtype.kind in "UOT":
        return [str(v) for v in np.ravel(values)] if values.ndim == 1 else values.astype(str)
    return values.astype(np.uint8) if values.dtype == bool else values
