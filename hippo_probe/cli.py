"""The ``hippo-probe`` command.

Each subsystem contributes its subcommands from a small ``_cli`` module (argument parsing
only; the heavy imports happen when a command runs), so ``hippo-probe --help`` is fast and
never imports torch. The subcommands, in the order ``--help`` shows them:
``world-stats`` (:mod:`hippo_probe.trial_stats._cli`), ``train``, ``evaluate`` and
``export-network`` (:mod:`hippo_probe.training._cli`), ``record`` and ``networks``
(:mod:`hippo_probe.model._cli`), ``baselines`` (:mod:`hippo_probe.baselines._cli`),
``import-nwb`` and the recording tools (:mod:`hippo_probe.recording._cli`), ``main`` and
``figures`` (:mod:`hippo_probe._main`). What they share is in
:mod:`hippo_probe._cli_common`.
"""

from __future__ import annotations

import sys

from . import _main
from ._cli_common import Parser, plain_warnings
from .baselines import _cli as baselines_cli
from .model import _cli as model_cli
from .recording import _cli as recording_cli
from .training import _cli as training_cli
from .trial_stats import _cli as trial_stats_cli

#: The modules that define ``add_commands(subparsers)``, in the order shown by --help.
COMMAND_MODULES = (trial_stats_cli, training_cli, model_cli, baselines_cli, recording_cli,
                   _main)


def build_parser() -> Parser:
    parser = Parser(
        prog="hippo-probe",
        description="Recurrent networks that navigate like rats, recorded like real cells.")
    from ._version import __version__
    parser.add_argument("--version", action="version", version=f"hippo_probe {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module in COMMAND_MODULES:
        module.add_commands(sub)
    return parser


def main(argv=None) -> int:
    """Run ``hippo-probe argv``; returns the exit status: 0, or 2 after one line on stderr
    for a usage error or bad input (``--help`` and ``--version`` return 0)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as done:   # --help, --version, or a usage error (already one line)
        return int(done.code or 0)
    try:
        with plain_warnings(args.command):
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
