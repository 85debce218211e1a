"""The ``.hp`` accessor of xarray objects: ``result.hp.plot()`` and ``rec.hp.plot()``.

Registered as soon as anything that makes a recording or a result is imported (the
recording and analysis packages), without importing matplotlib: the plot module is loaded
on the first call.
"""

import xarray as xr


@xr.register_dataarray_accessor("hp")
@xr.register_dataset_accessor("hp")
class HippoProbeAccessor:
    """``result.hp.plot()``: the natural plot of a hippo_probe result or recording, as a
    Figure (:func:`hippo_probe.plot.plot_result`)."""

    def __init__(self, obj):
        self._obj = obj

    def plot(self, **kwargs):
        """Plot the result; keyword arguments go to the specific plot helper."""
        from .plot import plot_result

        return plot_result(self._obj, **kwargs)
