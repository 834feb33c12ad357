"""The package's layers, as its imports show them (every import: at module level, inside a
function, or for type checking only), checked by walking each module's syntax tree:

- ``core/`` (the model) and ``wire/`` import nothing else of the package;
- ``bag/`` imports only ``wire/`` and, of the core, only ``core/stick_slip.py`` and
  ``core/effort.py`` (the one definitions of the SSI, a stuck bit and the drive's effort
  figures, which import only numpy: the bag tools stay light);
- ``session/`` never imports ROS; ROS (rclpy and the message packages) is imported only in
  ``ros/``, and ``ros/`` holds no ``argparse`` (command lines live in ``cli/``);
- nothing outside ``cli/`` imports ``cli/``;
- no two modules import each other, directly or round a longer circle.
"""

from __future__ import annotations

import ast
from functools import cache
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "drill_sim"
ROS_MODULES = {"rclpy", "rcl_interfaces", "std_msgs", "std_srvs", "geometry_msgs", "sensor_msgs",
               "diagnostic_msgs", "rosgraph_msgs", "builtin_interfaces", "rosidl_runtime_py",
               "ament_index_python"}
# a layer -> the layers of the package it may import besides itself (None: any)
MAY_IMPORT: dict[str, set[str] | None] = {
    "core": set(),
    "wire": set(),
    "bag": {"wire"},
}
# single modules a layer may import besides its layers: leaves that import nothing heavy
MAY_IMPORT_MODULES: dict[str, set[str]] = {"bag": {"drill_sim.core.stick_slip",
                                                   "drill_sim.core.effort"}}
LEAF_IMPORTS = {"__future__", "collections", "math", "numpy", "typing"}   # nothing of the package


def module_name(path: Path, root: Path = PACKAGE) -> str:
    rel = path.relative_to(root.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def imports_of(source: str, module: str, is_package: bool) -> set[str]:
    """Every module ``source`` (the module ``module``) imports, absolute names."""
    found: set[str] = set()
    base = module.split(".") if is_package else module.split(".")[:-1]
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                stem = base[:len(base) - (node.level - 1)]
                target = ".".join(stem + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            found.add(target)
            # ``from . import x`` / ``from .a import b``: b may itself be a module
            found.update(f"{target}.{a.name}" for a in node.names)
    return found


@cache
def _raw_imports(root: Path = PACKAGE) -> dict[str, set[str]]:
    """Each module's name -> every module it imports (absolute names), read once."""
    return {module_name(p, root): imports_of(p.read_text(), module_name(p, root),
                                             p.name == "__init__.py")
            for p in root.rglob("*.py")}


def package_modules(root: Path = PACKAGE, extra: dict[str, str] | None = None
                    ) -> dict[str, set[str]]:
    """Each module of the package -> the modules (package's own: existing ones only; others:
    their top-level name) it imports. ``extra``: more modules (path in the package -> source),
    added to the graph as if they were there."""
    raws = dict(_raw_imports(root))
    for rel, text in (extra or {}).items():
        name = module_name(root.parent / rel, root)
        raws[name] = imports_of(text, name, rel.endswith("__init__.py"))
    sources = raws
    graph: dict[str, set[str]] = {}
    for name, raw in raws.items():
        own = {m for m in raw if m in sources and m != name}
        outside = {m.split(".")[0] for m in raw if not m.startswith(root.name)}
        graph[name] = own | outside
    return graph


def layer(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def violations(graph: dict[str, set[str]], package: str = "drill_sim") -> list[str]:
    """Every import that breaks the layers' rules, in words."""
    found = []
    for module, targets in sorted(graph.items()):
        own = layer(module)
        for target in sorted(targets):
            theirs = layer(target) if target.startswith(package + ".") else None
            if theirs is None:                       # outside the package
                if target in ROS_MODULES and own != "ros":
                    found.append(f"{module} imports {target}: ROS is imported only in ros/")
                if target == "argparse" and own == "ros":
                    found.append(f"{module} imports argparse: command lines live in cli/")
                continue
            if theirs == own:
                continue
            allowed = MAY_IMPORT.get(own)
            if target in MAY_IMPORT_MODULES.get(own, ()):
                continue
            if allowed is not None and theirs not in allowed:
                found.append(f"{module} imports {target}: {own}/ may import only "
                             + (", ".join(f"{a}/" for a in sorted(allowed)) or "itself"))
            if theirs == "cli":
                found.append(f"{module} imports {target}: nothing outside cli/ imports cli/")
    return found


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The package's import circles (strongly connected groups of more than one module)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    groups: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in graph:
                continue
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                groups.append(sorted(group))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return groups


def _without_packages(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """Imports of a package's ``__init__`` re-exports are not circles of their modules: an
    ``__init__`` that imports its submodules, and a submodule that imports a sibling through
    it, are left out of the circle search."""
    packages = {m for m in graph if (PACKAGE.parent / m.replace(".", "/") / "__init__.py").exists()}
    return {m: {t for t in ts if t not in packages} for m, ts in graph.items()
            if m not in packages}


def test_the_layers_hold():
    found = violations(package_modules())
    assert not found, "\n".join(found)


def test_the_leaves_other_layers_may_import_stay_leaves():
    graph = package_modules()
    for leaf in set().union(*MAY_IMPORT_MODULES.values()):
        assert graph[leaf] <= LEAF_IMPORTS, (leaf, graph[leaf] - LEAF_IMPORTS)


def test_no_import_circles():
    found = circles(_without_packages(package_modules()))
    assert not found, found


@pytest.mark.parametrize(("module", "line", "words"), [
    ("drill_sim/core/x.py", "from ..wire import cdr", "core/ may import only itself"),
    ("drill_sim/core/x.py", "from ..session.rules import start", "core/ may import only"),
    ("drill_sim/wire/x.py", "from ..core.rig import Rig", "wire/ may import only itself"),
    ("drill_sim/bag/x.py", "from ..core import Rig", "bag/ may import only wire/"),
    ("drill_sim/bag/x.py", "from ..core.metrics import Metrics", "bag/ may import only wire/"),
    ("drill_sim/session/x.py", "import rclpy", "ROS is imported only in ros/"),
    ("drill_sim/cli/x.py", "from rclpy.node import Node", "ROS is imported only in ros/"),
    ("drill_sim/ros/x.py", "import argparse", "command lines live in cli/"),
    ("drill_sim/ros/x.py", "from ..cli.checks import number", "nothing outside cli/ imports"),
    ("drill_sim/core/x.py", "if True:\n    from drill_sim.wire import cdr", "core/ may import"),
])
def test_a_forbidden_import_is_caught(module, line, words):
    """The rules' check itself: the package with one forbidden import added."""
    found = violations(package_modules(extra={module: line + "\n"}))
    assert any(words in f for f in found), found


def test_a_circle_is_caught():
    graph = package_modules(extra={
        "drill_sim/core/a_.py": "from .b_ import x\n",
        "drill_sim/core/b_.py": "from typing import TYPE_CHECKING\n"
                                "if TYPE_CHECKING:\n    from .a_ import y\n"})
    assert ["drill_sim.core.a_", "drill_sim.core.b_"] in circles(graph)
