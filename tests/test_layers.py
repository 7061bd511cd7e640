"""The layers of pkm_pin (DESIGN.md, "Layers"): no import cycle, and every module imports
only from its own layer and the layers below.

Imports are read from the source (AST): lazy imports inside functions count, imports
under ``if TYPE_CHECKING:`` do not (they never run). ``from pkg import name`` counts as an
import of ``pkg.name`` when that is a module of pkm_pin, else of ``pkg``; the parent
packages that Python runs on the way are not counted (every import would run
``pkm_pin/__init__.py``). ``pkm_pin/formulas/`` importing nothing of pkm_pin is held by
tests/test_formulas_independence.py.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "pkm_pin"

#: Every module of pkm_pin (dotted name under pkm_pin; "pkm_pin" is the package itself)
#: by layer, with why the layer is where it is. A module imports from its own layer and
#: those below only.
LAYERS: dict[int, tuple[str, tuple[str, ...]]] = {
    0: ("foundations that need nothing above them: errors, tolerances, screw algebra, "
        "numba helpers, the engine's compiled linear algebra and stages, the papers' "
        "formulas",
        ("errors", "tolerances", "screws", "compiling", "checkpoint", "engine.linalg",
         "engine.stages", "formulas", "formulas.orthoglide", "formulas.rpr3",
         "formulas.serial_reduction", "formulas.stewart")),
    1: ("descriptions: URDF reading and the closure model with its readers",
        ("urdf", "model", "model.closure_model", "model.extended_urdf", "model.mjcf",
         "model.pinned", "model.structure", "model.chain_urdf")),
    2: ("kinematics of one configuration: compiled leg kinematics, the Pinocchio pass, "
        "serial chains, the assembly record whose twists that pass verifies, the default "
        "output chosen from one configuration's motions and the independent sub-mechanisms "
        "split from the tree and its closures",
        ("newton", "kernels", "tree_kernel", "output_kernel", "twists", "serial", "assembly",
         "output_choice", "submechanisms")),
    3: ("the closure solver, the Leg whose solve and inverse kinematics call it, why "
        "a linkage does not assemble (closure_gaps: open loops, joints at a limit), and the "
        "tree solved for some of its output's pose coordinates (output_driver)",
        ("solve", "leg", "closure_gaps", "output_driver")),
    4: ("screw analysis of one or N poses: the engine's driver, Analysis, transmission, "
        "closed-loop dynamics, the compiled general elimination of a linkage's analysis",
        ("engine", "engine.core", "analysis", "output_maps", "transmission", "dynamics",
         "general_kernel")),
    5: ("position problems and studies built on the solver and the analysis (trajectory: "
        "the efforts along a motion, on the closed-loop dynamics; simulation: its forward "
        "dynamics; dynamic_indices: actuator-space and output inertias, gravity maps)",
        ("position", "modes", "sweep", "workspace", "sensitivity", "tree_sensitivity",
         "calibration", "trajectory", "simulation", "dynamic_indices")),
    6: ("the general backend: Linkage, the general elimination over one tree and its "
        "closures, on the solver, the analysis and the studies",
        ("linkage",)),
    7: ("the facade: Mechanism, one closure model read by the per-leg engine or the "
        "general backend; io reads every file format into one",
        ("mechanism", "io")),
    8: ("outputs and applications of the facades: reports, scenes, plots, the CLI, the "
        "cross-check, the example builders, the package's public names",
        ("report", "scene", "view", "view_linkage", "plots", "cli",
         "crosscheck", "builders", "builders.__main__", "builders.design",
         "builders.dietmaier", "builders.loops", "builders.orthoglide", "builders.pinned",
         "builders.planar", "builders.serial_chains", "builders.spatial",
         "builders.urdf_writer", "builders.extended_urdf", "pkm_pin")),
}


def _module_name(path: Path) -> str:
    """``pkm_pin/engine/core.py`` → ``engine.core``; a package's ``__init__.py`` is the
    package; ``pkm_pin/__init__.py`` is ``pkm_pin``."""
    parts = path.relative_to(ROOT).with_suffix("").parts
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts) or "pkm_pin"


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in sorted(ROOT.rglob("*.py"))}


def _type_checking_nodes(tree: ast.AST) -> set[int]:
    """Ids of the nodes under ``if TYPE_CHECKING:`` (its body, not its else)."""
    skip = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            skip |= {id(n) for stmt in node.body for n in ast.walk(stmt)}
    return skip


def imports(source: str, name: str, package: bool, modules) -> list[tuple[str, int]]:
    """The modules of pkm_pin (names as in :data:`LAYERS`) that the source of module
    ``name`` imports at run time, with the line of each import; ``package``: the source
    is a package's ``__init__.py``; ``modules``: the names that are modules."""
    tree = ast.parse(source)
    skip = _type_checking_nodes(tree)
    full = "pkm_pin" if name == "pkm_pin" else f"pkm_pin.{name}"
    pkg = full if package else full.rsplit(".", 1)[0]

    def local(dotted: str) -> str | None:
        short = "pkm_pin" if dotted == "pkm_pin" else dotted.removeprefix("pkm_pin.")
        return short if dotted.split(".")[0] == "pkm_pin" and short in modules else None

    out = []
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            out += [(m, node.lineno) for a in node.names if (m := local(a.name))]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = pkg.split(".")[:len(pkg.split(".")) - node.level + 1]
                base = ".".join(up + ([base] if base else []))
            for a in node.names:
                m = local(f"{base}.{a.name}") or local(base)
                if m:
                    out.append((m, node.lineno))
    return [(m, line) for m, line in dict.fromkeys(out) if m != name]


def _graph() -> dict[str, list[tuple[str, int]]]:
    modules = _modules()
    return {name: imports(path.read_text(), name, path.name == "__init__.py", modules)
            for name, path in modules.items()}


def _layer_of() -> dict[str, int]:
    return {m: layer for layer, (_, names) in LAYERS.items() for m in names}


def _where(name: str, line: int) -> str:
    return f"{_modules()[name].relative_to(ROOT.parent)}:{line}"


def _cycles(graph: dict[str, list[tuple[str, int]]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w, _ in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def _circle(graph: dict[str, list[tuple[str, int]]], comp: list[str]) -> str:
    """A shortest circle of imports through the first module of the cycle ``comp``, each
    step with its file and line."""
    start = comp[0]
    came: dict[str, tuple[str, int]] = {}
    queue = [start]
    while queue:
        a = queue.pop(0)
        for b, line in graph[a]:
            if b in comp and b not in came:
                came[b] = (a, line)
                queue.append(b)
        if start in came:
            break
    steps, b = [], start
    while True:
        a, line = came[b]
        steps.append(f"{_where(a, line)} imports {b}")
        b = a
        if b == start:
            break
    return " -> ".join(reversed(steps))


def test_every_module_is_in_one_layer():
    """Every module of pkm_pin is in exactly one layer of LAYERS, and LAYERS names no
    module that does not exist."""
    listed = [m for _, names in LAYERS.values() for m in names]
    twice = sorted({m for m in listed if listed.count(m) > 1})
    assert not twice, f"in more than one layer of LAYERS (tests/test_layers.py): {twice}"
    modules = _modules()
    missing = [f"{p.relative_to(ROOT.parent)} ({m})" for m, p in modules.items()
               if m not in listed]
    assert not missing, ("modules in no layer: add each to LAYERS in tests/test_layers.py, "
                         "in the lowest layer that holds everything it imports: "
                         + ", ".join(missing))
    stale = sorted(set(listed) - set(modules))
    assert not stale, f"LAYERS (tests/test_layers.py) names modules that do not exist: {stale}"


def test_no_import_cycle():
    """No two modules of pkm_pin import each other, directly or around a circle, lazy
    imports included."""
    graph = _graph()
    messages = []
    for comp in _cycles(graph):
        messages.append(f"{' / '.join(comp)}: {_circle(graph, comp)}")
    assert not messages, "import cycles inside pkm_pin:\n" + "\n".join(messages)


def test_no_module_imports_a_higher_layer():
    """No module imports a module of a higher layer (DESIGN.md, "Layers"), lazy imports
    included."""
    layer = _layer_of()
    graph = _graph()
    up = [f"{_where(a, line)}: {a} (L{layer[a]}) imports {b} (L{layer[b]})"
          for a in sorted(graph) if a in layer
          for b, line in graph[a] if b in layer and layer[b] > layer[a]]
    assert not up, ("imports of a higher layer (move the code to the lower module, or pass "
                     "what it needs as an argument):\n" + "\n".join(up))


@pytest.mark.parametrize("source, expected", [
    ("from . import screws\nfrom .solve import solve_from\n", [("screws", 1), ("solve", 2)]),
    ("def f():\n    from .view import node_name\n", [("view", 2)]),
    ("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .mechanism import M\n"
     "else:\n    import pkm_pin.leg\n", [("leg", 5)]),
    ("import numpy\nfrom pkm_pin.engine.linalg import jacobi\nfrom pkm_pin import Leg\n",
     [("engine.linalg", 2), ("pkm_pin", 3)]),
])
def test_imports_are_read_lazy_included_type_checking_excluded(source, expected):
    """The reader finds relative, absolute and lazy imports of pkm_pin's modules, the
    package itself for a name it re-exports, and skips type-checking imports."""
    assert imports(source, "kernels", False, _modules()) == expected
