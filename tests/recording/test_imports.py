"""`recording` never imports torch or the simulator (it must work on rodent data alone)."""

import ast
from pathlib import Path

import hippo_probe.recording

FORBIDDEN = ("torch", "hippo_probe.world", "hippo_probe.model", "hippo_probe.tasks",
             "hippo_probe.training", "hippo_probe.baselines")
RELATIVE_FORBIDDEN = ("world", "model", "tasks", "training", "baselines")


def test_no_torch_or_simulator_imports():
    package = Path(hippo_probe.recording.__file__).parent
    for path in package.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                names = [node.module or ""]
                if node.level == 2:       # from ..x import y
                    assert names[0].split(".")[0] not in RELATIVE_FORBIDDEN, (path, names)
            else:
                continue
            for name in names:
                assert not name.startswith(FORBIDDEN), (path.name, name)

