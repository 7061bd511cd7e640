"""The hand-written formulas are an independent witness of the Pinocchio path."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

FORMULAS = Path(__file__).resolve().parents[1] / "pkm_pin" / "formulas"
PINOCCHIO_PATH = Path(__file__).resolve().parents[1] / "pkm_pin"


def _imports(path: Path) -> list[tuple[str, int]]:
    names = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names += [(a.name, 0) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            names.append((node.module or "", node.level))
    return names


@pytest.mark.parametrize("module", sorted(FORMULAS.glob("*.py")), ids=lambda p: p.stem)
def test_formulas_import_only_numpy_and_the_standard_library(module):
    """No formulas module imports pkm_pin, pinocchio, or anything relative outside formulas/."""
    allowed = {"__future__", "typing", "numpy", "dataclasses", "collections", "math"}
    for name, level in _imports(module):
        if level:  # relative: only siblings inside formulas/ (e.g. `from . import rpr3`)
            assert level == 1 and module.name == "__init__.py" or name == "", (module, name)
        else:
            assert name.split(".")[0] in allowed, (module.name, name)


@pytest.mark.parametrize("module", ["leg.py", "analysis.py", "mechanism.py", "screws.py",
                                    "serial.py", "urdf.py", "position.py"])
def test_pinocchio_path_does_not_import_the_formulas(module):
    """The modules of the Pinocchio path never import pkm_pin.formulas."""
    for name, _ in _imports(PINOCCHIO_PATH / module):
        assert "formulas" not in name, (module, name)
