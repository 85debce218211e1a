"""The one atomic-write mechanism: refusals, clean-up of dead writers' temporaries."""

import os
import subprocess
import sys
import textwrap
import time

import pytest

from hippo_probe import _atomic
from hippo_probe._atomic import atomic_path, remove_stale, temporary_beside, write_text


def test_a_failed_write_leaves_the_previous_file_and_no_temporary(tmp_path):
    dest = write_text(tmp_path / "log.json", "old")
    with pytest.raises(RuntimeError, match="boom"):
        with atomic_path(dest, overwrite=True) as tmp:
            tmp.write_text("half")
            raise RuntimeError("boom")
    assert dest.read_text() == "old"
    assert os.listdir(tmp_path) == ["log.json"]


def test_without_overwrite_an_existing_file_is_refused_naming_the_argument(tmp_path):
    dest = write_text(tmp_path / "a.txt", "kept")
    with pytest.raises(FileExistsError, match="`out` already exists"):
        write_text(dest, "new", overwrite=False, what="out")
    assert dest.read_text() == "kept"


def test_a_file_that_appears_during_the_write_is_kept(tmp_path):
    dest = tmp_path / "a.txt"
    with pytest.raises(FileExistsError, match="appeared while this was being written"):
        with atomic_path(dest) as tmp:
            tmp.write_text("mine")
            dest.write_text("theirs")          # another writer finished first
    assert dest.read_text() == "theirs"
    assert os.listdir(tmp_path) == ["a.txt"]


def test_a_directory_is_swapped_in_whole(tmp_path):
    dest = tmp_path / "store"
    for value in ("1", "2"):
        with atomic_path(dest, overwrite=True) as tmp:
            tmp.mkdir()
            (tmp / "x").write_text(value)
    assert (dest / "x").read_text() == "2"
    assert os.listdir(tmp_path) == ["store"]


KILLED = textwrap.dedent("""
    import sys, time
    from hippo_probe._atomic import atomic_path
    with atomic_path(sys.argv[1], overwrite=True) as tmp:
        open(tmp, "wb").close()               # a 0-byte temporary, as torch.save leaves
        print(tmp, flush=True)
        time.sleep(600)
""")


def test_a_killed_writers_temporary_is_removed_by_the_next_write(tmp_path):
    proc = subprocess.Popen([sys.executable, "-c", KILLED, str(tmp_path / "checkpoint.pt")],
                            stdout=subprocess.PIPE, text=True)
    tmp = tmp_path / os.path.basename(proc.stdout.readline().strip())
    assert tmp.exists() and tmp.stat().st_size == 0
    remove_stale(tmp_path)                     # its writer is alive: kept
    assert tmp.exists()
    proc.kill()
    proc.wait()
    write_text(tmp_path / "checkpoint.pt", "resumed")
    assert os.listdir(tmp_path) == ["checkpoint.pt"]


def test_a_temporary_from_another_host_is_removed_only_when_old(tmp_path, monkeypatch):
    monkeypatch.setattr(_atomic, "_HOST", "elsewhere")
    other = temporary_beside(tmp_path / "r.zarr")
    other.mkdir()
    monkeypatch.undo()
    assert remove_stale(tmp_path) == []        # may be a live writer on that host
    old = time.time() - _atomic.STALE_AFTER_S - 60
    os.utime(other, (old, old))
    assert remove_stale(tmp_path) == [other]
    assert not other.exists()
