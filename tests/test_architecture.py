"""The pipeline points one way: no import cycles, and no module imports a higher layer.

Layers, lowest first (docs/architecture.md draws them):

0. core: the System, results, tolerances, budgets, validation, exact arithmetic;
1. design: observer gains and the observer kinds;
2. spec: reading spec files and the packaged examples, the designs the top-level functions
   take (inputs) and the JSON Schemas;
3. analyses: structure, stability, simulation and the documents' estimators;
4. pipeline: analyze and certify;
5. renderers: text, JSON and HTML reports;
6. interface: the command line, ``ssecert.testing`` and the package itself.

Every import counts, also one inside a function; only imports under
``if TYPE_CHECKING:`` (annotations) are left out.
"""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "ssecert"

LAYERS = {
    0: (
        "ssecert._version",
        "ssecert.base",
        "ssecert.numerics",
        "ssecert.tolerances",
        "ssecert.budget",
        "ssecert.results",
        "ssecert.system",
        "ssecert.noise",
        "ssecert.parallel",
        "ssecert.context",
        "ssecert.solvers",
    ),
    1: ("ssecert.design", "ssecert.observers"),
    2: ("ssecert.spec", "ssecert.examples", "ssecert.inputs", "ssecert.schemas"),
    3: ("ssecert.structure", "ssecert.stability", "ssecert.simulation", "ssecert.estimators"),
    4: ("ssecert.analyze", "ssecert.certify", "ssecert.design.search", "ssecert.synthesize"),
    5: ("ssecert.report", "ssecert.experiments"),
    6: (
        "ssecert.cli",
        "ssecert.testing",
        "ssecert.__main__",
        "ssecert",
    ),
}


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _layer(module: str) -> int:
    best, best_len = None, -1
    for layer, prefixes in LAYERS.items():
        for prefix in prefixes:
            inside = (
                module.startswith(prefix + ".") and prefix != "ssecert"
            )  # the root: itself only
            if (module == prefix or inside) and len(prefix) > best_len:
                best, best_len = layer, len(prefix)
    assert best is not None, f"{module} is in no layer: add it to LAYERS"
    return best


def _type_checking_lines(tree: ast.AST) -> set[int]:
    lines: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for child in node.body:
                lines.update(range(child.lineno, (child.end_lineno or child.lineno) + 1))
    return lines


def _imports(module: str) -> set[str]:
    """The ssecert modules ``module`` imports (a package's submodules resolved)."""
    path = MODULES[module]
    tree = ast.parse(path.read_text(encoding="utf-8"))
    skip = _type_checking_lines(tree)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    out: set[str] = set()
    for node in ast.walk(tree):
        if getattr(node, "lineno", None) in skip:
            continue
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name.split(".")[0] == "ssecert")
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != "ssecert":
                continue
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                out.add(sub if sub in MODULES else target)
    out.discard(module)
    return {m for m in out if m in MODULES}


GRAPH = {m: _imports(m) for m in MODULES}


def test_every_module_is_in_a_layer():
    for module in MODULES:
        _layer(module)


@pytest.mark.parametrize("module", sorted(MODULES))
def test_no_module_imports_a_higher_layer(module):
    mine = _layer(module)
    upward = sorted(m for m in GRAPH[module] if _layer(m) > mine)
    assert not upward, f"{module} (layer {mine}) imports {upward}"


def test_no_module_sits_below_its_package():
    # importing ssecert.a.b runs ssecert/a/__init__.py first: a module placed in a lower layer
    # than its package would bring the package's layer with it
    for module in MODULES:
        parts = module.split(".")
        for i in range(2, len(parts)):
            package = ".".join(parts[:i])
            assert _layer(module) >= _layer(package), (
                f"{module} (layer {_layer(module)}) is inside {package} (layer {_layer(package)})"
            )


def test_no_import_cycles():
    state: dict[str, int] = {}  # 1 on the stack, 2 done
    stack: list[str] = []

    def visit(module: str) -> None:
        state[module] = 1
        stack.append(module)
        for dep in sorted(GRAPH[module]):
            # a package imports its own submodules to gather them; that is not a cycle
            if module.startswith(dep + ".") and MODULES[dep].name == "__init__.py":
                continue
            if state.get(dep) == 1:
                cycle = stack[stack.index(dep) :] + [dep]
                pytest.fail("import cycle: " + " -> ".join(cycle))
            if dep not in state:
                visit(dep)
        stack.pop()
        state[module] = 2

    for module in sorted(GRAPH):
        if module not in state:
            visit(module)


def test_the_graph_is_what_it_seems():
    # the walker finds imports of every kind, so an empty graph cannot pass the tests above
    assert "ssecert.observers.registry" in GRAPH["ssecert.observers.luenberger"]
    assert "ssecert.system" in GRAPH["ssecert.spec.core"]
    assert "ssecert.spec.core" in GRAPH["ssecert.spec"]
    assert "ssecert.report.html" in GRAPH["ssecert"]  # the function-level import counts
    assert _layer("ssecert.observers.sso") == 1 and _layer("ssecert.report.html") == 5


@pytest.mark.slow
def test_certify_builds_the_observer_and_decides_sparse_observability_once(monkeypatch):
    # the observer built for the checks is the one simulated; the stealthy scenario replays
    # the certificate's own witness
    import importlib

    from ssecert.examples import load_example

    modules = {
        name: importlib.import_module(name)
        for name in (
            "ssecert.certify",
            "ssecert.analyze",
            "ssecert.simulation.engine",
            "ssecert.stability.checks",
            "ssecert.structure.sparse",
            "ssecert.observers",
        )
    }
    calls = {"sparse_observability": 0, "build_observer": 0}

    def counting(name, function):
        def wrapped(*args, **kwargs):
            calls[name] += 1
            return function(*args, **kwargs)

        return wrapped

    for module in modules.values():
        for name in calls:
            if hasattr(module, name):
                monkeypatch.setattr(module, name, counting(name, getattr(module, name)))
    result = modules["ssecert.certify"].certify(load_example("ugv"), seed=0, runs=2, steps=20)
    assert not isinstance(result.simulations["stealthy"], dict)  # simulated, not skipped
    assert calls == {"sparse_observability": 1, "build_observer": 1}


def _code_strings(path: Path) -> list[tuple[int, str]]:
    """The string constants of a module's code (docstrings left out), with their lines."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    docstrings = {
        id(node.body[0].value)
        for node in ast.walk(tree)
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
        and node.body
        and isinstance(node.body[0], ast.Expr)
        and isinstance(node.body[0].value, ast.Constant)
    }
    return [
        (node.lineno, node.value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant) and isinstance(node.value, str)
        if id(node) not in docstrings
    ]


@pytest.mark.slow
def test_no_module_outside_the_observers_names_a_kind():
    # a kind is one module: what the spec reader, the checks, the design command and the
    # strategies need of it, it declares (ObserverKind); "ogd" is also a gain's name
    from ssecert.observers import GAIN_CHOICES, get_kind, observer_kinds

    names = {n for k in observer_kinds() for n in (k, *get_kind(k).aliases)} - set(GAIN_CHOICES)
    found = [
        f"{module}:{line}: {text!r}"
        for module, path in MODULES.items()
        # the documents' experiments configure the observers their documents name, as a spec
        # file does
        if not module.startswith(("ssecert.observers", "ssecert.experiments"))
        for line, text in _code_strings(path)
        if text in names
    ]
    assert not found, found


def test_the_package_root_holds_public_modules_and_subpackages():
    # private helpers live in a subpackage (ssecert.base and the others), so the root's files
    # name the public modules; _version is the packaging convention
    private = sorted(
        p.name
        for p in PACKAGE.glob("*.py")
        if p.name.startswith("_") and p.name not in ("__init__.py", "__main__.py", "_version.py")
    )
    assert not private, private


def test_the_design_command_lives_beside_the_gains_and_stays_importable_where_documented():
    import ssecert
    import ssecert.synthesize as old
    from ssecert.design import search

    assert ssecert.design is search.design
    assert old.design_observer is search.design_observer
    assert old.compare_designs is search.compare_designs
    assert set(search.__all__) <= set(old.__all__)
    # the gains' package does not bring the command (and analyze) with it
    assert "ssecert.design.search" not in GRAPH["ssecert.design"]
