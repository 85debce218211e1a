"""A writer killed in the middle of save_recording leaves nothing or the previous store."""

import os
import shutil
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest
import xarray as xr

from hippo_probe.errors import RecordingError
from hippo_probe.recording import open_recording, save_recording

from .conftest import make_network_recording

WRITER = textwrap.dedent("""
    import os, sys, time
    import numpy as np
    from hippo_probe.recording import RecordingConfig, from_arrays, save_recording
    import hippo_probe._atomic as atomic

    dest, mode, flag = sys.argv[1:4]
    n, units = 100_000, 32
    rng = np.random.default_rng(1)
    rec = from_arrays(np.arange(n) * 0.01, rng.random((n, 2)),
                      activity=rng.standard_normal((n, units), dtype=np.float32))
    if mode == "between-renames":
        rename = os.rename
        def slow_rename(a, b):
            rename(a, b)
            if str(b).split("/")[-1].startswith(".") and ".old-" in str(b):
                open(flag, "w").close()
                time.sleep(600)
        atomic.os.rename = slow_rename
    # small chunks: many files, so the kill lands in the middle of the data
    save_recording(rec, dest, overwrite=True, config=RecordingConfig(chunk_bytes=2**18))
""")


def _start(tmp_path, dest, mode):
    script = tmp_path / "writer.py"
    script.write_text(WRITER)
    flag = tmp_path / f"{dest.name}.flag"
    proc = subprocess.Popen([sys.executable, str(script), str(dest), mode, str(flag)])
    return proc, flag


def _kill_when(conditions, timeout=60):
    """Poll the writers together; SIGKILL each as soon as its condition holds."""
    pending = dict(conditions)
    end = time.monotonic() + timeout
    while pending:
        for proc, condition in list(pending.items()):
            if condition():
                proc.send_signal(signal.SIGKILL)
                del pending[proc]
            elif proc.poll() is not None or time.monotonic() > end:
                for other in pending:
                    other.kill()
                pytest.fail(f"a writer ended (rc={proc.returncode}) before the moment to "
                            "kill it")
        time.sleep(0.002)


def _chunks_written(dest):
    partial = list(dest.parent.glob(f".{dest.name}.partial-*"))
    return bool(partial) and any((partial[0] / "activity" / "c").rglob("*"))


def test_killed_writer_leaves_previous_store_or_nothing(tmp_path):
    previous = make_network_recording()
    replaced = tmp_path / "replaced.zarr"      # killed while writing the new version's data
    swapped = tmp_path / "swapped.zarr"        # killed between the two renames
    save_recording(previous, replaced)
    save_recording(previous, swapped)
    runs = {dest: _start(tmp_path, dest, mode) for dest, mode in
            ((replaced, "mid-write"), (swapped, "between-renames"))}
    _kill_when({runs[replaced][0]: lambda: _chunks_written(replaced),   # mid-data
                runs[swapped][0]: runs[swapped][1].exists})             # old set aside
    for proc, _ in runs.values():
        proc.wait(timeout=30)
        assert proc.returncode == -signal.SIGKILL

    # the half-written temp store never opens as a recording (a copy: opening anything
    # in tmp_path removes the dead writer's temporaries)
    (partial,) = tmp_path.glob(".replaced.zarr.partial-*")
    shutil.copytree(partial, tmp_path / "copy" / "half.zarr")
    with pytest.raises(RecordingError, match="half-written"):
        open_recording(tmp_path / "copy" / "half.zarr")
    shutil.rmtree(tmp_path / "copy")
    # killed after setting the old store aside: destination absent until the next open
    assert not swapped.exists()
    # the overwritten store is the previous complete version, untouched, and opening it
    # cleaned what the dead writers left beside it: the partial store is gone, and the
    # store set aside is back at its name, with a warning
    with pytest.warns(UserWarning, match="swapped.zarr was being replaced .* restored"):
        xr.testing.assert_identical(open_recording(replaced).load(), previous)
    assert not list(tmp_path.glob(".replaced.zarr.partial-*"))
    assert not list(tmp_path.glob(".swapped.zarr.old-*"))
    xr.testing.assert_identical(open_recording(swapped).load(), previous)
    # the next saves clean up what the dead writers left
    for dest in (replaced, swapped):
        save_recording(previous, dest, overwrite=True)
    assert sorted(os.listdir(tmp_path)) == [
        "replaced.zarr", "swapped.zarr", "swapped.zarr.flag", "writer.py"]
    assert np.isfinite(open_recording(swapped).activity.values).all()


CONCURRENT = textwrap.dedent("""
    import sys, time
    import numpy as np
    from hippo_probe.recording import from_arrays, save_recording
    import hippo_probe.recording.store as store

    dest, value, start = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
    n = 20_000
    rec = from_arrays(np.arange(n) * 0.01, np.zeros((n, 2)),
                      activity=np.full((n, 4), value, dtype=np.float32))
    write = store._write
    def slow_write(*args, **kwargs):     # both writers past the existence check before either ends
        write(*args, **kwargs)
        time.sleep(max(0.0, start - time.time()) + value)
    store._write = slow_write
    try:
        save_recording(rec, dest)
    except FileExistsError as err:
        print("refused:", err)
        sys.exit(3)
""")


def test_two_writers_to_one_new_path_one_wins_and_one_is_refused(tmp_path):
    """Two concurrent ``save_recording(..., overwrite=False)`` to one new path: the first
    to finish keeps its store, the later one raises instead of silently replacing it."""
    script = tmp_path / "writer.py"
    script.write_text(CONCURRENT)
    dest = tmp_path / "shared.zarr"
    start = time.time() + 8          # both have imported and started writing by then
    procs = [subprocess.Popen([sys.executable, str(script), str(dest), str(v), str(start)],
                              stdout=subprocess.PIPE, text=True) for v in (1.0, 3.0)]
    codes = [p.wait(timeout=120) for p in procs]
    assert codes == [0, 3], [p.stdout.read() for p in procs]
    assert "appeared while this was being written" in procs[1].stdout.read()
    assert float(open_recording(dest)["activity"][0, 0]) == 1.0
    assert not list(tmp_path.glob(".shared.zarr*"))           # nothing half-written left


def test_lazily_made_nan_activity_fails_the_save_and_leaves_nothing(tmp_path):
    """validate() cannot see values of a dask-backed recording without computing them;
    the save checks each block as it writes it."""
    rec = make_network_recording()
    activity = rec["activity"].values.copy()
    activity[7, 1] = np.nan
    lazy = rec.assign(activity=rec["activity"].copy(data=activity)).chunk({"time": 50})
    dest = tmp_path / "nan.zarr"
    with pytest.raises(RecordingError, match=r"`activity` must not contain NaN or inf; "
                                             r"found nan at index \(7, 1\)"):
        save_recording(lazy, dest)
    assert os.listdir(tmp_path) == []


def test_a_live_writers_store_set_aside_is_left_alone_by_other_writers(tmp_path):
    """An overwrite between its two renames is not undone by a save of another name."""
    import hippo_probe._atomic as atomic

    rec = make_network_recording()
    save_recording(rec, tmp_path / "a.zarr")
    live = tmp_path / f".a.zarr{atomic.OLD}{atomic._HOST}-{os.getpid()}-0000abcd"
    os.rename(tmp_path / "a.zarr", live)
    save_recording(rec, tmp_path / "b.zarr")          # cleans the folder first and last
    assert live.exists() and not (tmp_path / "a.zarr").exists()
    # once that writer is gone, the next write in the folder restores the copy
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True).stdout.strip()
    orphan = tmp_path / f".a.zarr{atomic.OLD}{atomic._HOST}-{dead}-0000abcd"
    os.rename(live, orphan)
    with pytest.warns(UserWarning, match="a.zarr was being replaced .* restored"):
        save_recording(rec, tmp_path / "b.zarr", overwrite=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.zarr", "b.zarr"]
