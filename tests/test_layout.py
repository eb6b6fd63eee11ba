"""The package's layout: data flows down (no import circles at any depth) and no folder grows into a flat heap.

The import graph is read from the source (AST), not from ``sys.modules``: function-level imports count (a lazy
import is still a dependency), and an import of a package counts as an import of its ``__init__``.
"""

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "evoik_pin"
#: Modules side by side in one folder at most (``__init__`` included): more, and the folder needs sub-packages.
MAX_MODULES_PER_FOLDER = 15


def _modules(root: Path) -> dict[str, Path]:
    """Dotted module name -> file, for every module of the package at ``root`` (a package is its __init__)."""
    mods = {}
    for f in root.rglob("*.py"):
        parts = (root.name, *f.relative_to(root).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        mods[".".join(parts)] = f
    return mods


def import_graph(root: Path) -> dict[str, set[str]]:
    """module -> the package's modules it imports (anywhere in its body), by name."""
    mods = _modules(root)

    def known(name: str) -> str | None:  # the module itself, else the package that holds the imported name
        while name and name not in mods:
            name = name.rpartition(".")[0]
        return name or None

    graph: dict[str, set[str]] = {m: set() for m in mods}
    for m, f in mods.items():
        here = m.split(".") if f.name == "__init__.py" else m.split(".")[:-1]
        for node in ast.walk(ast.parse(f.read_text(encoding="utf-8"), str(f))):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = ".".join(here[:len(here) - node.level + 1] + ([node.module] if node.module else [])) \
                    if node.level else (node.module or "")
                # `from pkg import module` depends on the module; `from pkg import name` on pkg's __init__
                names = [f"{base}.{a.name}" if f"{base}.{a.name}" in mods else base for a in node.names]
            else:
                continue
            for name in names:
                target = known(name)
                if target is not None and target != m:
                    graph[m].add(target)
    return graph


def import_circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan's algorithm, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    circles = []
    for start in graph:
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            v, children = work[-1]
            for w in children:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                    break
                if w in on_stack:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    component = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        component.append(w)
                        if w == v:
                            break
                    if len(component) > 1:
                        circles.append(sorted(component))
    return circles


def test_the_graph_sees_lazy_relative_and_package_imports():
    graph = import_graph(PACKAGE)
    assert "evoik_pin.solvers.batch.ray_actors" in graph["evoik_pin.solvers.batch.solve_many_call"]  # inside a function
    assert "evoik_pin.solvers" in graph["evoik_pin.solvers.paper.de"]  # `from .. import register`: the __init__
    assert "evoik_pin.solvers.lm" in graph["evoik_pin.solvers.search.memetic"]  # a package: its __init__


def test_circles_are_found():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": {"e"}}
    assert import_circles(graph) == [["a", "b", "c"]]


def test_no_module_imports_one_that_imports_it_back():
    circles = import_circles(import_graph(PACKAGE))
    assert not circles, "import circles: " + "; ".join(" <-> ".join(c) for c in circles)


def test_no_folder_holds_more_than_15_modules():
    folders = {f.parent for f in PACKAGE.rglob("*.py")}
    crowded = {str(folder.relative_to(PACKAGE.parent)): n for folder in sorted(folders)
               if (n := len(list(folder.glob("*.py")))) > MAX_MODULES_PER_FOLDER}
    assert not crowded, f"folders with more than {MAX_MODULES_PER_FOLDER} modules: {crowded}"


#: The solver sub-packages and the ones each may import (docs/ARCHITECTURE.md: batch above search above lm and paper).
SOLVER_LAYERS = {"batch": {"search", "lm"}, "search": {"lm", "paper"}, "paper": set(), "lm": set()}


def test_solver_sub_packages_import_only_the_layers_below_them():
    graph = import_graph(PACKAGE)
    prefix = "evoik_pin.solvers."
    wrong = []
    for module, imported in graph.items():
        if not module.startswith(prefix) or module[len(prefix):].split(".")[0] not in SOLVER_LAYERS:
            continue
        layer = module[len(prefix):].split(".")[0]
        for target in imported:
            other = target[len(prefix):].split(".")[0] if target.startswith(prefix) else None
            if other in SOLVER_LAYERS and other != layer and other not in SOLVER_LAYERS[layer]:
                wrong.append(f"{module} -> {target}")
    assert not wrong, "solver layers imported upward or sideways: " + "; ".join(sorted(wrong))
