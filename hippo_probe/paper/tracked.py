"""The repository's tracked copies of the figures: ``paper_figures/png/*.png`` (shown by
the README) and ``paper_figures/RESULTS.md``.

They are refreshed only on request, naming the clone (``hippo-probe figures
--refresh-tracked CLONE``, ``hippo-probe main --refresh-tracked CLONE``; ``bash
quickstart.sh main`` passes its own), from a folder where every figure was just made at
the paper size, so the repository shows what its own networks give at the study's scale.
The package never finds a clone to write into by itself.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from .._atomic import atomic_path

#: Folder of the README's figure copies, inside the repository.
PNG = "paper_figures/png"
#: The tracked claims table, inside the repository.
RESULTS = "paper_figures/RESULTS.md"


def check_repository(repository) -> Path:
    """The clone ``repository`` whose tracked copies are refreshed; raises
    FileNotFoundError if it is not one (no ``paper_figures/png`` in it)."""
    if repository is None or not (Path(repository) / PNG).is_dir():
        raise FileNotFoundError(
            f"the tracked copies ({PNG}/, {RESULTS}) are files of a clone of the "
            f"hippo_probe repository; none at {repository}")
    return Path(repository)


def refresh_tracked(figures, results, *, repository) -> list[Path]:
    """Copy freshly made figures and RESULTS.md over the repository's tracked copies.

    Only figures that already have a tracked copy (of the same file name) are copied (the
    README shows a chosen few); RESULTS.md is required.

    Parameters
    ----------
    figures : iterable of path
        The figures (``<name>.png``) made by this run (a stale file of an earlier run is
        never copied).
    results : path
        The RESULTS.md made by this run.
    repository : str or os.PathLike
        The clone whose copies are refreshed.

    Returns
    -------
    list of pathlib.Path
        The tracked files written.

    Raises
    ------
    FileNotFoundError
        No clone of the repository, or no ``results``.
    """
    root, results = check_repository(repository), Path(results)
    if not results.is_file():
        raise FileNotFoundError(f"{results} not found: RESULTS.md is written before the "
                                f"tracked copies are refreshed")
    pairs = [(Path(new), root / PNG / Path(new).name) for new in figures]
    pairs = [(new, old) for new, old in pairs if old.exists() and new.exists()]
    pairs.append((results, root / RESULTS))
    for new, old in pairs:
        with atomic_path(old, overwrite=True, what="tracked copy") as tmp:
            shutil.copyfile(new, tmp)
    return [old for _, old in pairs]
