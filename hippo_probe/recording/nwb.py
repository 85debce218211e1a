"""NWB import and export (pynwb imported when called)."""


def from_nwb(path, epoch="wake", **options):
    raise NotImplementedError("from_nwb is being written")


def to_nwb(rec, path, **options):
    raise NotImplementedError("to_nwb is being written")
