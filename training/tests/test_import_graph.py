"""The training package has no import cycles, counting imports made inside functions too.

A cycle hidden in a function body still couples the modules: neither can be read, tested or
changed alone, and moving the import to the top of the file turns it into an ImportError. The
graph is built from the sources with `ast`, so a module is never run to find what it imports."""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = "training"
PACKAGE_DIR = Path(__file__).resolve().parents[1]

# Modules every other one may import, and the only ones of the package each may import itself.
FOUNDATION = {
    "training.errors": set(),
    "training.files": {"training.errors"},
    "training.onnx_metadata": set(),
    "training.progress": set(),
}


def package_modules(root: Path, package: str) -> dict[str, Path]:
    """Dotted module name -> source file, for every .py under `root` outside tests/."""
    modules = {}
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root)
        if rel.parts[0] == "tests":
            continue
        parts = [package, *rel.with_suffix("").parts]
        if parts[-1] == "__init__":
            parts.pop()
        modules[".".join(parts)] = path
    return modules


def _package_of(module: str, path: Path) -> str:
    return module if path.name == "__init__.py" else module.rpartition(".")[0]


def _resolve(base: str, name: str, known: dict[str, Path]) -> str | None:
    """The known module `base.name` is, else `base` itself when it is one (an attribute of it)."""
    full = f"{base}.{name}" if name else base
    if full in known:
        return full
    return base if base in known else None


def _constant_string(node) -> str | None:
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return node.value
    return None


def imports_of(module: str, path: Path, known: dict[str, Path]) -> dict[str, int]:
    """Package modules `module` imports -> line of the first such import. Counts `import p.x`,
    `from p.x import y`, `from p import x`, relative forms, and `__import__` /
    `importlib.import_module` with a literal name, wherever they appear in the file."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    here = _package_of(module, path)
    found: dict[str, int] = {}

    def add(target: str | None, line: int) -> None:
        if target and target != module:
            found.setdefault(target, line)

    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name == PACKAGE or alias.name.startswith(PACKAGE + "."):
                    add(_resolve(alias.name, "", known), node.lineno)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base_parts = here.split(".")
                if node.level > 1:
                    base_parts = base_parts[:-(node.level - 1)]
                base = ".".join(base_parts + ([node.module] if node.module else []))
            else:
                base = node.module or ""
            if not (base == PACKAGE or base.startswith(PACKAGE + ".")):
                continue
            for alias in node.names:
                add(_resolve(base, alias.name, known), node.lineno)
        elif isinstance(node, ast.Call) and node.args:
            func = node.func
            called = (func.id if isinstance(func, ast.Name)
                      else func.attr if isinstance(func, ast.Attribute) else None)
            if called in ("__import__", "import_module"):
                name = _constant_string(node.args[0])
                if name and (name == PACKAGE or name.startswith(PACKAGE + ".")):
                    add(_resolve(name, "", known), node.lineno)
    return found


def import_graph(root: Path = PACKAGE_DIR, package: str = PACKAGE) -> dict[str, dict[str, int]]:
    known = package_modules(root, package)
    return {m: imports_of(m, p, known) for m, p in known.items()}


def cycle_groups(graph: dict[str, dict[str, int]]) -> list[list[str]]:
    """The modules of each cycle group, those that all reach one another (the strongly connected
    components of more than one module, Tarjan's algorithm), sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    groups: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                groups.append(sorted(group))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(groups)


def find_cycles(graph: dict[str, dict[str, int]]) -> list[list[str]]:
    """One shortest cycle through each cycle group, in a stable order."""
    return [_cycle_in(group, graph) for group in cycle_groups(graph)]


def _cycle_in(group: list[str], graph: dict[str, dict[str, int]]) -> list[str]:
    """A shortest cycle through the group's first module, staying inside the group."""
    members = set(group)
    start = group[0]
    previous = {start: None}
    frontier = [start]
    while frontier:
        nxt = []
        for v in frontier:
            for w in sorted(graph[v]):
                if w == start:
                    path = [v]
                    while previous[path[-1]] is not None:
                        path.append(previous[path[-1]])
                    return list(reversed(path)) + [start]
                if w in members and w not in previous:
                    previous[w] = v
                    nxt.append(w)
        frontier = nxt
    raise AssertionError(f"no cycle through {start} in {group}")


def describe(cycle: list[str], graph: dict[str, dict[str, int]]) -> str:
    steps = [f"{a} (line {graph[a][b]})" for a, b in zip(cycle, cycle[1:])]
    return " -> ".join(steps + [cycle[-1]])


def test_the_package_has_no_import_cycle():
    graph = import_graph()
    groups = cycle_groups(graph)
    assert not groups, "import cycles in training/:\n" + "\n".join(
        f"{describe(_cycle_in(g, graph), graph)}  (modules in this cycle group: {', '.join(g)})"
        for g in groups)


@pytest.mark.parametrize("module", sorted(FOUNDATION))
def test_errors_and_file_helpers_import_nothing_else_of_the_package(module):
    graph = import_graph()
    assert module in graph, f"{module} is missing"
    extra = sorted(set(graph[module]) - FOUNDATION[module])
    assert not extra, f"{module} imports {extra}"


def test_the_graph_sees_every_import_form(tmp_path):
    pkg = tmp_path / "training"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("MODEL_FPS = 60\n")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from .b import thing\n")
    (pkg / "b.py").write_text("def f():\n    from training.c import g\n")
    (pkg / "c.py").write_text("import training.d\n")
    (pkg / "d.py").write_text("from . import e\nfrom training import MODEL_FPS\n")
    (pkg / "e.py").write_text("def f():\n    return __import__('training.sub.s', fromlist=['x'])\n")
    (pkg / "sub" / "s.py").write_text("from .. import a\nimport numpy\nfrom os import path\n")
    (pkg / "tests").mkdir()
    (pkg / "tests" / "test_x.py").write_text("from training import a\n")

    graph = import_graph(pkg, "training")
    assert "training.tests.test_x" not in graph
    assert graph["training.a"] == {"training.b": 1}
    assert graph["training.b"] == {"training.c": 2}
    assert graph["training.c"] == {"training.d": 1}
    assert graph["training.d"] == {"training.e": 1, "training": 2}
    assert graph["training.e"] == {"training.sub.s": 2}
    assert graph["training.sub.s"] == {"training.a": 1}
    cycles = find_cycles(graph)
    assert len(cycles) == 1
    cycle = cycles[0]
    assert cycle[0] == cycle[-1] == "training.a"
    assert set(cycle) == {"training.a", "training.b", "training.c", "training.d", "training.e",
                          "training.sub.s"}
    assert "training.a (line 1) -> training.b (line 2)" in describe(cycle, graph)


def test_two_separate_cycles_are_both_named():
    graph = {"p.a": {"p.b": 1}, "p.b": {"p.a": 3}, "p.c": {"p.d": 1}, "p.d": {"p.e": 2},
             "p.e": {"p.c": 5, "p.a": 1}, "p.f": {}}
    assert cycle_groups(graph) == [["p.a", "p.b"], ["p.c", "p.d", "p.e"]]
    assert find_cycles(graph) == [["p.a", "p.b", "p.a"], ["p.c", "p.d", "p.e", "p.c"]]
    assert find_cycles({"p.a": {"p.b": 1}, "p.b": {}}) == []
