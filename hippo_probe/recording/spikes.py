"""``poisson_spikes``: a recording of rates (or of a network's signed activity) as spikes.

A network's units are noise-free, so any tuning at all, however weak, beats time-shift
shuffles with thousands of samples: every unit passes the significance tests that define
cell classes in animals (place, head-direction, speed...). Drawing Poisson spikes from each
unit's activity at a realistic rate puts the units under the counting noise of real
cells, so that the same tests mean the same thing on both.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._validators import check_nonnegative_int, check_number
from ..errors import RecordingError
from .schema import SIGNED_KINDS
from .validate import check_analysable


def poisson_spikes(rec, mean_rate, seed=0):
    r"""Spike counts drawn from each unit's activity taken as a rate.

    Each unit's activity :math:`a_u(t)` is made non-negative (minus its minimum over the
    recording for a signed kind such as the LSTM's ``lstm_hidden``; used as it is for
    ``rate``), scaled to the mean firing rate ``mean_rate`` and sampled:

    .. math::

        r_u(t) = \bar r\,\frac{a_u(t) - m_u}{\langle a_u - m_u \rangle_t}, \qquad
        n_u(t) \sim \mathrm{Poisson}(r_u(t)\,\delta t),

    with :math:`m_u` the unit's minimum (0 for a rate) and :math:`\delta t` the sample
    interval (``attrs['dt']``). A signed unit whose activity is constant has rate 0 (no
    spikes); a constant positive rate fires steadily at ``mean_rate``; a rate unit that is
    0 throughout stays silent. The shape of each unit's tuning is kept; only its scale is
    set, so ``mean_rate`` is a statement about the cells being compared with (e.g. the
    median rate of a real session's units), not a free knob of the tuning.

    :math:`m_u` and the mean are taken over the recording passed: spikes drawn from a
    subset of trials (``select_trials`` first) are scaled to that subset, and differ from
    the same trials cut out of spikes drawn over the whole recording. On a dask-backed
    recording both reductions run at once, in one streaming pass, when this is called;
    the draws themselves stay lazy.

    Parameters
    ----------
    rec : xarray.Dataset
        A recording whose ``activity_kind`` is not already ``"spike_count"``; may be
        dask-backed (the result then stays lazy, one random stream per chunk, so it depends
        on the chunking as well as on ``seed``).
    mean_rate : float
        Mean firing rate of every unit, in Hz (> 0).
    seed : int
        Seed of the Poisson draws (>= 0).

    Returns
    -------
    xarray.Dataset
        ``rec`` with ``activity`` replaced by spike counts per sample (float32, as the
        schema stores every activity),
        ``activity_kind = "spike_count"``, and attrs ``spikes_from`` (the original kind),
        ``spikes_mean_rate_hz`` and ``spikes_seed``.

    Raises
    ------
    RecordingError
        ``rec`` already holds spike counts, or has no ``dt``.
    ValueError
        ``mean_rate`` not a positive finite number, ``seed`` not an int >= 0.

    Examples
    --------
    >>> import numpy as np
    >>> from hippo_probe.recording import from_arrays
    >>> t = np.arange(5000) * 0.02
    >>> rec = from_arrays(t, np.zeros((5000, 2)), activity=np.sin(t)[:, None],
    ...                   activity_kind="lstm_hidden", dt=0.02)
    >>> spikes = poisson_spikes(rec, mean_rate=5.0)
    >>> round(float(spikes.activity.sum()) / 100.0)      # 100 s at 5 Hz
    5
    """
    mean_rate = check_number("mean_rate", mean_rate, low=0)     # > 0 and finite
    seed = check_nonnegative_int("seed", seed)
    if not isinstance(rec, xr.Dataset):
        raise TypeError(f"`rec` must be a recording (an xarray.Dataset, schema v1); got "
                        f"{type(rec).__name__}")
    if "activity" not in rec.data_vars:
        raise RecordingError("`rec` must contain `activity` (the rates to draw spikes from)")
    check_analysable(rec)
    if rec.sizes.get("unit", 0) == 0 or rec.sizes.get("time", 0) == 0:
        raise RecordingError(f"`rec.activity` must have at least one unit and one sample; "
                             f"got {rec.sizes.get('time', 0)} samples x "
                             f"{rec.sizes.get('unit', 0)} units")
    kind = rec.attrs.get("activity_kind")
    if kind == "spike_count":
        raise RecordingError("`rec` already holds spike counts (activity_kind "
                             "'spike_count'): there is no rate to draw spikes from")
    dt = rec.attrs.get("dt")
    if dt is None or not np.isfinite(dt) or dt <= 0:
        raise RecordingError(f"`rec.attrs['dt']` must be the sample interval in s; got {dt!r}")
    act = rec["activity"]
    floor = act.min("time") if kind in SIGNED_KINDS else xr.zeros_like(
        act.isel(time=0, drop=True))
    # mean(a - m) = mean(a) - m: both reductions stream over the chunks together (taking
    # the mean of a - m would hold every chunk until the minimum is known)
    mean = act.mean("time") - floor
    floor, mean = xr.align(*_computed(floor, mean))
    # rate per sample, r dt; a constant unit (mean 0) gets 0, not NaN
    scale = xr.where(mean > 0, mean_rate * dt / mean.where(mean > 0, 1.0), 0.0)
    expected = ((act - floor) * scale).clip(min=0.0).transpose(*act.dims)
    counts = xr.DataArray(_draw(expected.data, seed), dims=act.dims, coords=act.coords,
                          attrs={**act.attrs, "units": "count",
                                 "long_name": "spike count per sample"})
    out = rec.assign(activity=counts)
    out.attrs.update(activity_kind="spike_count", spikes_from=str(kind),
                     spikes_mean_rate_hz=mean_rate, spikes_seed=seed)
    return out


def _computed(*arrays):
    """The per-unit reductions as numpy (one pass over a lazy recording)."""
    import dask

    return dask.compute(*arrays)


def _draw(expected, seed):
    """Poisson counts of the expected counts ``expected`` (numpy or dask)."""
    if not hasattr(expected, "dask"):
        return np.random.default_rng(seed).poisson(expected).astype(np.float32)

    def block(x, block_info=None):
        where = block_info[0]["chunk-location"]
        return np.random.default_rng([seed, *where]).poisson(x).astype(np.float32)

    return expected.map_blocks(block, dtype=np.float32)
