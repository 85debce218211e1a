"""The one atomic-write mechanism: refusals, clean-up of dead writers' temporaries."""

import ast
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from hippo_probe import _atomic
from hippo_probe._atomic import (atomic_path, remove_stale, save_figure, temporary_beside,
                                 write_text)


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


# ------------------------------------------------------------------ one mechanism
PACKAGE = Path(_atomic.__file__).parent
#: Module-level writers and renames; each must run inside ``with atomic_path(...)``.
WRITERS = {("os", "replace"), ("os", "rename"), ("shutil", "move"), ("torch", "save"),
           ("json", "dump"), ("pickle", "dump"), ("np", "save"), ("np", "savez"),
           ("np", "savez_compressed"), ("pynwb", "NWBHDF5IO"), ("zarr", "open_group"),
           ("zarr", "open")}
#: Methods that write their receiver to a file.
WRITING_METHODS = {"to_zarr", "to_netcdf", "savefig", "write_text", "write_bytes"}
#: (file, function): why a write there is not a second mechanism.
ALLOWED = {
    ("_atomic.py", "_publish"): "the mechanism itself",
    ("_atomic.py", "remove_stale"): "the mechanism's recovery: renames back the copy an "
                                    "overwrite set aside before it died",
    ("recording/store.py", "_write"): "called inside save_recording's atomic_path (or on "
                                      "a URL, where object stores have no rename)",
    ("recording/chunk_files.py", "_write_file"): "a chunk file of the store that "
                                                  "save_recording's _write writes",
    ("tasks.py", "_discard"): "renames a damaged cache block aside to delete it",
    ("_main.py", "_make_run_in_worker"): "a run's message log, written as it goes so that "
                                         "it shows how far a failed run got; not data",
    ("_atomic.py", "exclusive_lock"): "a lock file (flock) holding its holder's pid, not "
                                      "data: never read back as results",
}


def _writes_mode(call) -> bool:
    modes = [a.value for a in call.args[1:2] if isinstance(a, ast.Constant)]
    modes += [k.value.value for k in call.keywords
              if k.arg == "mode" and isinstance(k.value, ast.Constant)]
    return any(isinstance(m, str) and set(m) & set("wax+") for m in modes)


def _direct_writes(tree):
    """(function, what, line) of every file write or rename not inside ``atomic_path``."""
    found = []

    def visit(node, parents):
        if isinstance(node, ast.Call):
            fn, what = node.func, None
            if isinstance(fn, ast.Attribute) and isinstance(fn.value, ast.Name) \
                    and (fn.value.id, fn.attr) in WRITERS:
                if fn.attr not in ("NWBHDF5IO", "open_group", "open") or _writes_mode(node):
                    what = f"{fn.value.id}.{fn.attr}"
            elif isinstance(fn, ast.Attribute) and fn.attr in WRITING_METHODS:
                what = f".{fn.attr}()"
            elif isinstance(fn, ast.Attribute) and fn.attr in ("replace", "rename") \
                    and len(node.args) == 1 and not node.keywords \
                    and getattr(fn.value, "id", None) != "dataclasses":
                what = f"Path.{fn.attr}"          # tmp.replace(dest): a rename
            elif isinstance(fn, ast.Name) and fn.id == "open" and _writes_mode(node):
                what = "open(..., 'w')"
            atomic = any(isinstance(p, ast.With) and any(
                isinstance(i.context_expr, ast.Call)
                and getattr(i.context_expr.func, "id", None) == "atomic_path"
                for i in p.items) for p in parents)
            if what and not atomic:
                func = next((p.name for p in reversed(parents)
                             if isinstance(p, (ast.FunctionDef, ast.AsyncFunctionDef))),
                            "<module>")
                found.append((func, what, node.lineno))
        for child in ast.iter_child_nodes(node):
            visit(child, [*parents, node])

    visit(tree, [])
    return found


def test_every_file_the_package_writes_goes_through_atomic_path():
    """One implementation of write-then-rename: a write or rename
    outside ``with atomic_path(...)`` is a second mechanism, unless listed in ALLOWED."""
    stray = []
    scripts = PACKAGE.parent / "analyses"        # the repository's analysis scripts too
    for path in sorted(PACKAGE.rglob("*.py")) + sorted(scripts.glob("*.py")):
        rel = path.relative_to(PACKAGE if path.is_relative_to(PACKAGE) else
                               PACKAGE.parent).as_posix()
        for func, what, line in _direct_writes(ast.parse(path.read_text(), str(path))):
            if (rel, func) not in ALLOWED:
                stray.append(f"{rel}:{line} {func}: {what}")
    assert not stray, "writes outside hippo_probe._atomic.atomic_path:\n" + "\n".join(stray)


def test_the_scan_sees_a_second_mechanism():
    """The scan itself: a direct writer of log.json is found."""
    old = ast.parse(textwrap.dedent("""
        def save_log(run_dir, log):
            with open(run_dir / "log.json", "w") as f:
                json.dump(log, f)
            tmp = run_dir / ".log.tmp"
            tmp.write_text("{}")
            tmp.replace(run_dir / "log.json")
            with atomic_path(run_dir / "ok.json") as tmp:
                tmp.write_text("{}")
    """))
    assert [w for _, w, _ in _direct_writes(old)] == [
        "open(..., 'w')", "json.dump", ".write_text()", "Path.replace"]


def test_a_saved_pdf_is_the_same_bytes_on_every_run(tmp_path, monkeypatch):
    # Without this a PDF carries its creation time, and two fresh clones' figures
    # (README, "Reproducibility") can no longer be compared byte for byte.
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    monkeypatch.delenv("SOURCE_DATE_EPOCH", raising=False)
    fig, ax = plt.subplots()
    ax.plot([0, 1], [1, 0])
    first = save_figure(fig, tmp_path / "a.pdf").read_bytes()
    time.sleep(1.1)  # the PDF date has a resolution of one second
    second = save_figure(fig, tmp_path / "b.pdf").read_bytes()
    plt.close(fig)
    assert b"CreationDate" not in first
    assert first == second
