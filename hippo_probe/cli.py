"""The ``hippo-probe`` command.

Each subsystem contributes its subcommands from a small ``_cli`` module (argument parsing
only; the heavy imports happen when a command runs), so ``hippo-probe --help`` is fast and
never imports torch.
"""

from __future__ import annotations

import argparse
import importlib
import sys

# modules that define ``add_commands(subparsers)``; in the order shown by --help
_COMMAND_MODULES = (
    "hippo_probe.world._cli",
    "hippo_probe.training._cli",
    "hippo_probe.model._cli",
    "hippo_probe.baselines._cli",
    "hippo_probe.recording._cli",
    "hippo_probe._main",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="hippo-probe",
        description="Recurrent networks that navigate like rats, recorded like real cells.")
    from ._version import __version__
    parser.add_argument("--version", action="version", version=f"hippo_probe {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in _COMMAND_MODULES:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as err:
            if err.name == name:      # subsystem not built yet
                continue
            raise
        module.add_commands(sub)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.run(args) or 0)
    except (ValueError, FileNotFoundError, FileExistsError, IsADirectoryError,
            NotADirectoryError, PermissionError) as err:
        # bad input: one clear line, no traceback
        print(f"hippo-probe {args.command}: error: {err}", file=sys.stderr)
        return 2
    except ModuleNotFoundError as err:
        from ._optional import EXTRAS, missing

        if err.name not in EXTRAS:
            raise
        print(f"hippo-probe {args.command}: error: "
              f"{missing(err.name, f'hippo-probe {args.command}')}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
