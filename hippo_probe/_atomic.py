"""Atomic writes: the one mechanism by which the package puts a file or a store on disk.

Everything is written to a hidden temporary beside the destination and renamed into
place only when complete, so a crash (even ``kill -9``) leaves the previous file or the
new one at the destination, never half of one. Temporaries are named
``.NAME.partial-HOST-PID-UUID`` and a directory set aside by an overwrite
``.NAME.old-HOST-PID-UUID``; one whose writer is no longer running (same host, dead
process) or that is older than :data:`STALE_AFTER_S` is left over, and is cleaned by the
next write (or :func:`remove_stale` call) in that folder. A live writer's are never
touched, so writers of different names in one folder cannot undo each other's work.

Without ``overwrite`` the final step refuses an existing destination atomically (a hard
link for a file, a rename onto a non-empty directory for a store), so two concurrent
writers of one new path cannot both succeed.
"""

from __future__ import annotations

import errno
import os
import shutil
import socket
import time
import uuid
import warnings
from contextlib import contextmanager
from pathlib import Path

PARTIAL = ".partial-"
OLD = ".old-"
STALE_AFTER_S = 24 * 3600.0      # a temporary from another host is trusted this long
_HOST = socket.gethostname().replace("-", "_") or "host"


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:           # alive, owned by someone else
        return True
    return True


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        try:
            path.unlink()
        except FileNotFoundError:
            pass


def _owner_tag() -> str:
    return f"{_HOST}-{os.getpid()}-{uuid.uuid4().hex[:8]}"


def _is_stale(item: Path, marker: str, now: float) -> bool:
    """Whether the writer that named ``item`` (``…MARKER HOST-PID-UUID``) has stopped."""
    host, _, rest = item.name.rpartition(marker)[2].partition("-")
    pid = rest.split("-")[0]
    if host == _HOST and pid.isdigit():
        return not _pid_alive(int(pid))
    if not rest:                      # an older name without its writer: nobody owns it
        return True
    try:
        st = item.lstat()
        # a copy set aside is dated by its rename, which sets ctime, not a store's mtime
        since = max(st.st_mtime, st.st_ctime) if marker == OLD else st.st_mtime
        return now - since > STALE_AFTER_S
    except FileNotFoundError:
        return False


def remove_stale(folder) -> list[Path]:
    """Remove the temporaries in ``folder`` left by writers that died; returns them.

    Also removes a previous copy set aside by an overwrite (``.NAME.old-UUID``) once the
    new copy is in place at ``NAME``; if the overwrite died between its two renames
    (``NAME`` gone, the copy aside), the copy is renamed back to ``NAME``, with a warning.
    """
    folder = Path(folder)
    if not folder.is_dir():
        return []
    now = time.time()
    removed = []
    for item in folder.glob(f".*{PARTIAL}*"):
        if _is_stale(item, PARTIAL, now):
            _remove(item)
            removed.append(item)
    aside = []
    for item in folder.glob(f".*{OLD}*"):
        try:
            if _is_stale(item, OLD, now):
                aside.append((item.lstat().st_ctime, item))
        except FileNotFoundError:     # another cleanup took it meanwhile
            pass
    for _, item in sorted(aside, reverse=True):
        name = item.name[1:].rpartition(OLD)[0]
        if not name:
            continue
        if (folder / name).exists() or (folder / name).is_symlink():
            _remove(item)
            removed.append(item)
            continue
        try:
            os.rename(item, folder / name)          # the newest copy aside comes back
        except OSError as err:
            if err.errno in (errno.ENOENT, errno.EEXIST, errno.ENOTEMPTY):
                continue              # another cleanup restored one first
            raise
        else:
            warnings.warn(f"{folder / name} was being replaced when its writer stopped; "
                          f"its previous version (set aside as {item.name}) is restored",
                          UserWarning, stacklevel=3)
    return removed


def temporary_beside(dest: Path) -> Path:
    """A fresh hidden temporary path in ``dest``'s folder, named after ``dest``."""
    # the suffix is kept: some writers (pynwb, numpy) check or append it
    return dest.parent / f".{dest.name}{PARTIAL}{_owner_tag()}{dest.suffix}"


def _fsync(path: Path) -> None:
    with open(path, "rb") as f:
        os.fsync(f.fileno())


def _publish(tmp: Path, dest: Path, overwrite: bool, what: str) -> None:
    exists = dest.exists() or dest.is_symlink()
    if exists and dest.is_dir() != tmp.is_dir():
        raise FileExistsError(f"`{what}` {dest} is a {'directory' if dest.is_dir() else 'file'}"
                              f"; refusing to replace it with a "
                              f"{'directory' if tmp.is_dir() else 'file'}")
    if exists and not overwrite:      # it was absent when the write began
        raise FileExistsError(_appeared(what, dest))
    if tmp.is_dir():
        if exists:
            old = dest.parent / f".{dest.name}{OLD}{_owner_tag()}"
            os.rename(dest, old)
            try:
                os.rename(tmp, dest)
            except OSError as err:    # another process put a store back at dest meanwhile
                if err.errno in (errno.EEXIST, errno.ENOTEMPTY):
                    raise FileExistsError(_appeared(what, dest)) from None
                raise
            _remove(old)
            return
        try:                          # onto a non-empty directory this fails: no race
            os.rename(tmp, dest)
        except OSError as err:
            if err.errno in (errno.EEXIST, errno.ENOTEMPTY, errno.ENOTDIR, errno.EISDIR):
                raise FileExistsError(_appeared(what, dest)) from None
            raise
        return
    _fsync(tmp)
    if overwrite:
        os.replace(tmp, dest)
        return
    try:                              # a hard link never replaces: the atomic refusal
        os.link(tmp, dest)
    except FileExistsError:
        raise FileExistsError(_appeared(what, dest)) from None
    except OSError:                   # a filesystem without hard links
        if dest.exists():
            raise FileExistsError(_appeared(what, dest)) from None
        os.rename(tmp, dest)
        return
    tmp.unlink()


def _appeared(what: str, dest: Path) -> str:
    return (f"`{what}` appeared while this was being written (another writer?): {dest}; "
            f"it was kept. Pass overwrite=True to replace it")


def make_parent(dest, what: str = "path") -> None:
    """Create the folder ``dest`` goes into (and its parents), or say which part of the
    path is in the way (a file where a folder is needed)."""
    dest = Path(dest)
    try:
        dest.parent.mkdir(parents=True, exist_ok=True)
    except (FileExistsError, NotADirectoryError):
        blocker = next((p for p in [dest.parent, *dest.parent.parents]
                        if p.exists() and not p.is_dir()), dest.parent)
        raise NotADirectoryError(f"`{what}` {str(dest)!r} cannot be written: "
                                 f"{str(blocker)!r} is a file, not a folder") from None


@contextmanager
def atomic_path(dest, *, overwrite: bool = False, what: str = "path"):
    """Context manager yielding a temporary path to write; moved to ``dest`` on success.

    The body writes a file or a directory (a zarr store) at the yielded path. On a clean
    exit it is fsynced (a file) and renamed to ``dest``; on an exception, or if the
    destination exists and ``overwrite`` is False, it is deleted and ``dest`` is left as
    it was. Stale temporaries in the folder are removed first.

    Parameters
    ----------
    dest : str or os.PathLike
        The destination file or directory. Its folder is created if missing.
    overwrite : bool
        Replace an existing ``dest`` (a directory is swapped: old aside, new in, old
        deleted).
    what : str
        The argument's name, for error messages.

    Raises
    ------
    FileExistsError
        ``dest`` exists (or appeared during the write) and ``overwrite`` is False.
    """
    dest = Path(dest)
    if (dest.exists() or dest.is_symlink()) and not overwrite:
        raise FileExistsError(f"`{what}` already exists: {dest}; pass overwrite=True to "
                              f"replace it")
    make_parent(dest, what)
    remove_stale(dest.parent)
    tmp = temporary_beside(dest)
    try:
        yield tmp
        _publish(tmp, dest, overwrite, what)
        remove_stale(dest.parent)     # e.g. a copy set aside by an overwrite that died
    finally:
        if tmp.exists() or tmp.is_symlink():
            _remove(tmp)


def write_text(path, text: str, *, overwrite: bool = True, what: str = "path") -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    path = Path(path)
    with atomic_path(path, overwrite=overwrite, what=what) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path


def save_figure(fig, path, **savefig_kwargs) -> Path:
    """``fig.savefig`` to ``path`` atomically, in the format its suffix names.

    A PDF carries no creation date (unless ``metadata`` is passed), so the same figure
    gives the same bytes on every run and two fresh clones' outputs can be compared with
    ``cmp``.
    """
    path = Path(path)
    fmt = path.suffix.lstrip(".") or "png"
    if fmt == "pdf":
        savefig_kwargs.setdefault("metadata", {"CreationDate": None})
    with atomic_path(path, overwrite=True, what="path") as tmp:
        fig.savefig(tmp, format=fmt, **savefig_kwargs)
    return path


@contextmanager
def exclusive_lock(path, on_busy):
    """Hold an exclusive lock on the file ``path`` (made if absent) with this process's
    pid written in it, for the ``with`` block.

    When another process holds it, ``on_busy(holder)`` is called first (``holder``: the
    pid that process wrote, or "?"): raise there to refuse, or return to wait for the
    lock. The kernel drops a lock when its holder dies (kill -9 included), so no stale
    lock survives a crash. The file is never removed: removing it on release would let a
    late opener lock an unlinked file while the next holder locks a new one. Without
    POSIX locks (``fcntl``), the block runs unlocked.
    """
    try:
        import fcntl
    except ImportError:
        yield
        return
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a+") as handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            handle.seek(0)
            on_busy(handle.read().strip() or "?")
            fcntl.flock(handle, fcntl.LOCK_EX)
        handle.seek(0)
        handle.truncate()
        handle.write(str(os.getpid()))
        handle.flush()
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)
