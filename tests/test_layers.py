"""The package's layers: no module imports from a layer above its own, and no import cycle.

The flow of the tree is builder -> model/state -> energies -> solvers -> load paths ->
measurements -> pictures -> studies -> the command line. Each package may import only the
packages listed for it in :data:`ALLOWED` (its own is always allowed). Every ``import`` and
``from ... import`` counts, also those inside functions (a lazy import is still a
dependency), except under ``if TYPE_CHECKING:``.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1] / "tightknot"

#: Modules directly under tightknot/ that every layer may use (file output, Warp setup).
BASE = {"atomic", "warp_setup", "_lazy"}

_LOW = {"base", "rods", "contact"}
#: package -> the packages it may import.
ALLOWED: dict[str, set[str]] = {
    "base": set(),
    "rods": {"base"},
    "contact": {"base", "rods"},
    "solvers": _LOW,
    "knots": _LOW,                       # geometry, topology, measurements, scenes
    "loading": _LOW | {"solvers", "knots"},
    "viz": {"base", "knots"},            # pictures of states and measurements, never physics
    "study": _LOW | {"solvers", "knots", "loading", "viz"},
    "sweep": _LOW | {"solvers", "knots", "loading", "viz", "study"},
    "fem": _LOW | {"solvers", "knots", "loading"},
    "verification": {"base", "rods", "solvers"},
    "benchmarks": _LOW | {"solvers", "knots", "loading", "viz", "study", "sweep",
                          "verification"},
    "app": _LOW | {"solvers", "knots", "loading", "viz", "study", "sweep", "fem",
                   "verification", "benchmarks"},
}


def _module_name(path: Path) -> str:
    rel = path.relative_to(ROOT.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _layer(module: str) -> str | None:
    parts = module.split(".")
    if len(parts) < 2:
        return None  # the package itself: its public API re-exports every layer
    if parts[1] in BASE:
        return "base"
    return parts[1]


def _is_type_checking(node: ast.If) -> bool:
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or (
        isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING")


def _imports(path: Path) -> set[str]:
    """Absolute names of the tightknot modules that ``path`` imports."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    module = _module_name(path)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found: set[str] = set()

    def visit(node: ast.AST) -> None:
        if isinstance(node, ast.If) and _is_type_checking(node):
            for child in node.orelse:
                visit(child)
            return
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.startswith("tightknot"))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.startswith("tightknot"):
                # "from pkg import mod" imports the submodule when there is one.
                for a in node.names:
                    sub = f"{target}.{a.name}"
                    found.add(sub if _exists(sub) else target)
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(tree)
    return found


def _exists(module: str) -> bool:
    p = ROOT.parent / module.replace(".", "/")
    return p.with_suffix(".py").is_file() or (p / "__init__.py").is_file()


def _graph() -> dict[str, set[str]]:
    graph = {}
    for path in sorted(ROOT.rglob("*.py")):
        graph[_module_name(path)] = {m for m in _imports(path) if _exists(m)}
    return graph


def violations(graph: dict[str, set[str]]) -> list[str]:
    """Imports from a layer that :data:`ALLOWED` does not permit, one line each."""
    out = []
    for module, imported in sorted(graph.items()):
        own = _layer(module)
        if own is None:
            continue
        bad = sorted(m for m in imported
                     if _layer(m) not in (own, None) and _layer(m) not in ALLOWED[own])
        if bad:
            out.append(f"{module} ({own}) imports {bad}; {own} may import "
                       f"{sorted(ALLOWED[own])}")
    return out


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Import cycles: Tarjan's strongly connected components of more than one module, or
    a module importing itself."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found: list[list[str]] = []
    counter = [0]

    def strong(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                strong(w)
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
            if len(comp) > 1 or v in graph.get(v, ()):
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            strong(v)
    return found


GRAPH = _graph()


def test_the_rule_table_covers_every_package() -> None:
    layers = {_layer(m) for m in GRAPH} - {None}
    assert layers <= set(ALLOWED), f"packages without a rule: {layers - set(ALLOWED)}"


def test_no_import_from_a_higher_layer() -> None:
    assert not violations(GRAPH), "\n".join(violations(GRAPH))


def test_no_import_cycle() -> None:
    assert not cycles(GRAPH), f"import cycles: {cycles(GRAPH)}"


def test_the_checks_catch_what_they_look_for() -> None:
    # The checker on a made-up graph: a rod module importing a load path, and a cycle.
    bad = {"tightknot.rods.model": {"tightknot.loading.tie"}, "tightknot.loading.tie": set()}
    assert violations(bad) and "tightknot.rods.model" in violations(bad)[0]
    loop = {"tightknot.knots.a": {"tightknot.knots.b"}, "tightknot.knots.b": {"tightknot.knots.a"}}
    assert cycles(loop) == [["tightknot.knots.a", "tightknot.knots.b"]]
    # ... and the parser on this tree: a lazy import inside a function counts.
    assert "tightknot.knots.smoothing" in GRAPH["tightknot.knots.curves"]
