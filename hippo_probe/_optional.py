"""Optional dependencies: one message for a missing one."""

from __future__ import annotations

#: extra that brings each optional dependency
EXTRAS = {"torch": "model", "pynwb": "nwb", "distributed": "distributed",
          "pynapple": "pynapple", "skdim": "dimension"}


def missing(dependency: str, what: str) -> ModuleNotFoundError:
    """The error for ``what`` needing ``dependency``, naming the extra that installs it."""
    extra = EXTRAS.get(dependency, dependency)
    return ModuleNotFoundError(
        f"{what} needs {dependency}, which the core install of hippo_probe leaves out; "
        f"install it with: pip install 'hippo_probe[{extra}]'", name=dependency)
