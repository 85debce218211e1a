"""Where the repository's own files are, when the package runs from a clone of it.

The figure builders need a few files that are not package data (the NWB test session,
the hand-written notes of RESULTS.md, the tracked copies of the figures); each module
that needs one takes its path as an argument, defaulting to the repository's copy found
here.
"""

from __future__ import annotations

from pathlib import Path

#: The package's own folder (``hippo_probe/``), whose sources key the caches.
PACKAGE = Path(__file__).resolve().parents[1]
#: The repository checkout the package runs from, if it runs from one (an editable
#: install or ``python -m`` in a clone); ``None`` for an installed package.
REPOSITORY = PACKAGE.parent if (PACKAGE.parent / "pyproject.toml").is_file() \
    and (PACKAGE.parent / "paper_figures").is_dir() else None


def repository_file(relative: str, *, argument: str) -> Path:
    """The repository's file ``relative`` (e.g. ``"tests/data/A2929-200711.nwb"``).

    Parameters
    ----------
    relative : str
        Path inside the repository.
    argument : str
        The argument of the caller that takes the file's path instead, named in the
        error.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    FileNotFoundError
        Not running from a clone of the repository, or the clone lacks the file.
    """
    if REPOSITORY is None:
        raise FileNotFoundError(
            f"{relative} is a file of the hippo_probe repository, not of the installed "
            f"package, and no clone was found around {PACKAGE}; pass `{argument}` its path")
    path = REPOSITORY / relative
    if not path.is_file():
        raise FileNotFoundError(f"{path} not found (a file of the repository); pass "
                                f"`{argument}` its path")
    return path
