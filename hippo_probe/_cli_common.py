"""What every ``hippo-probe`` subcommand shares, one voice for all: :class:`Parser` (each
option's default shown in ``--help``, usage errors in one line), :func:`one_of` (an option
restricted to a few names, refused with the package's validator message), :func:`count`
and :func:`check_output` (an output path refused before the work starts, naming the
flag), and :func:`plain_warnings`. The subcommands' ``_cli`` modules import these;
:mod:`hippo_probe.cli` imports the ``_cli`` modules, so every arrow runs one way.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import warnings
from pathlib import Path

#: The package's folder: a warning raised from a file below it is the toolkit's own.
PACKAGE = Path(__file__).resolve().parent


@contextlib.contextmanager
def plain_warnings(command: str):
    """Print the toolkit's warnings as ``hippo-probe COMMAND: warning: ...``, one line
    like its errors, rather than as Python shows them (a file, a line number and a line of
    source inside the package, which mean nothing to a user of the command). Warnings of
    other libraries keep Python's form. Only the text is changed: whoever records warnings
    (``pytest.warns``, ``catch_warnings(record=True)``) still receives them all."""
    original = warnings.formatwarning

    def one_line(message, category, filename, lineno, line=None):
        if Path(filename).resolve().is_relative_to(PACKAGE):
            return f"hippo-probe {command}: warning: {message}\n"
        return original(message, category, filename, lineno, line)

    warnings.formatwarning = one_line
    try:
        yield
    finally:
        warnings.formatwarning = original


class HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """``--help`` with each option's default after its text, "(default: 0)".

    An option whose default is None says in its own text what happens without it
    ("default: the network's own"), which reads better than "(default: None)".
    """

    def _get_help_string(self, action):
        if action.default is None:
            return action.help
        return super()._get_help_string(action)


class Parser(argparse.ArgumentParser):
    """The parser of ``hippo-probe`` and of every subcommand (``add_subparsers`` makes its
    subparsers of the same class): :class:`HelpFormatter`, and a usage error is one line,
    like the errors of the commands themselves."""

    def __init__(self, *args, formatter_class=HelpFormatter, **kwargs):
        super().__init__(*args, formatter_class=formatter_class, **kwargs)

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see `{self.prog} --help`)\n")


def one_of(name: str, allowed):
    """``type=`` of an option restricted to ``allowed`` (give ``choices=allowed`` too, for
    the help): another value is refused with the package's message, "argument --task:
    `task` must be one of 'localization', ...; got 'maze'"."""
    from ._validators import check_option

    allowed = tuple(allowed)

    def parse(text):
        try:
            return check_option(name, text, allowed)
        except ValueError as err:
            raise argparse.ArgumentTypeError(str(err)) from None

    parse.__name__ = name
    return parse


def count(low: int = 1):
    """``type=`` of an option that counts something (trials, particles, steps): a whole
    number >= ``low``, else argparse's one line, "argument --trials: must be a whole number
    >= 1; got 0" (an option's own name, not the Python argument it becomes)."""
    def parse(text):
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be a whole number >= {low}; "
                                             f"got {text!r}") from None
        if value < low:
            raise argparse.ArgumentTypeError(f"must be a whole number >= {low}; got {value}")
        return value

    parse.__name__ = "count"
    return parse


#: What a ``kind="file"`` output may replace without --overwrite: a file of the kind the
#: command writes (a figure, a JSON of numbers), never e.g. a tracked text file.
OUTPUT_SUFFIXES = {"figure": (".png", ".pdf", ".svg"), "json": (".json",)}


def check_output(flag: str, path, *, kind: str = "store", overwrite: bool = False,
                 writes: str = "figure", example: str | None = None) -> Path:
    """Refuse, before any work starts, an output path the command could not write at its
    end; the message names the command-line ``flag``.

    Parameters
    ----------
    flag : str
        The option as typed, e.g. ``"--out"`` (or a positional's metavar, ``"DEST"``).
    path : str or os.PathLike
    kind : {"store", "file", "folder"}
        ``"store"``: a zarr store, refused if it exists unless ``overwrite`` (pass
        --overwrite); ``"file"``: a file of the kind ``writes`` replaced freely (an older
        figure or JSON of the command), any other existing file refused unless
        ``overwrite``, and refused if it is an existing folder; ``"folder"``: a folder
        written into, refused if it is a file.
    overwrite : bool
        The command's --overwrite.
    writes : {"figure", "json"}
        What a ``"file"`` output is (:data:`OUTPUT_SUFFIXES`).
    example : str, optional
        The file name suggested when a ``"file"`` output is given as a folder (default
        ``figure.png`` or ``numbers.json``, after ``writes``).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    FileExistsError, IsADirectoryError, NotADirectoryError, PermissionError
    """
    path = Path(path)
    if kind == "store" and (path.exists() or path.is_symlink()) and not overwrite:
        raise FileExistsError(f"{flag} {path} already exists; pass --overwrite to replace it")
    if kind == "file" and path.is_dir():
        example = example or ("numbers.json" if writes == "json" else "figure.png")
        raise IsADirectoryError(f"{flag} {path} is a folder; give a file name (e.g. "
                                f"{path / example})")
    if kind == "file" and path.is_file() and not overwrite \
            and path.suffix.lower() not in OUTPUT_SUFFIXES[writes]:
        raise FileExistsError(f"{flag} {path} exists and is not a {writes} file "
                              f"({', '.join(OUTPUT_SUFFIXES[writes])}) this command "
                              f"writes; pass --overwrite to replace it")
    if kind == "folder" and path.exists() and not path.is_dir():
        raise NotADirectoryError(f"{flag} {path} is a file; give a folder")
    # the nearest existing folder above it is where the output (or its folders) is made
    for parent in path.absolute().parents:
        if parent.exists():
            if not parent.is_dir():
                raise NotADirectoryError(f"{flag} {path}: {parent} is a file, not a folder")
            if not os.access(parent, os.W_OK | os.X_OK):
                raise PermissionError(f"{flag} {path}: no permission to write in {parent}")
            break
    return path
