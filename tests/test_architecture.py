"""The shape of the package: imports run one way, no cycles, only the command line prints, one engine.

Layers, top to bottom (a module may import its own layer and the layers below it):

    cli -> report/planning -> fitting -> scene/data -> loading/units/params -> core -> errors

The import graph is read from the source (``ast``), module-level and function-level imports alike, so
an import hidden in a function to dodge a cycle still counts.
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "adhfit"

#: (prefix, layer): the first matching prefix decides (longest prefixes first)
LAYERS = [("adhfit.cli", 7), ("adhfit.report", 6), ("adhfit.planning", 6), ("adhfit.fitting", 5),
          ("adhfit.scene", 4), ("adhfit.data", 4), ("adhfit.synthetic", 4), ("adhfit.readers", 4), ("adhfit.physical", 4),
          ("adhfit.loading", 3), ("adhfit.simulation", 3), ("adhfit.membranes", 3), ("adhfit.histories", 2), ("adhfit.units", 3), ("adhfit.params", 3),
          ("adhfit.core", 2), ("adhfit.exact", 2),
          ("adhfit.errors", 1)]

#: Upward imports that are allowed, each a function-level import of a presentation hook: a result
#: object draws itself in a notebook (``.plot()``, ``_repr_html_``) with the report layer's code.
#: Every entry must exist (a stale entry fails) and must stay inside a function.
LAZY_HOOKS = {("adhfit.fitting.result", "adhfit.report.fit_plot"),
              ("adhfit.fitting.result", "adhfit.report.html"),
              ("adhfit.physical", "adhfit.report.plots")}


def _module(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _resolve(name: str) -> str:
    """The module a dotted name refers to: ``adhfit.a.b.c`` -> the longest prefix that is a module."""
    parts = name.split(".")
    for k in range(len(parts), 0, -1):
        base = PACKAGE.parent.joinpath(*parts[:k])
        if base.with_suffix(".py").is_file() or (base / "__init__.py").is_file():
            return ".".join(parts[:k])
    return name


def _imports() -> dict[str, list[tuple[str, bool]]]:
    """module -> [(imported adhfit module, at module level?)]."""
    graph = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        mod = _module(path)
        pkg = mod if path.name == "__init__.py" else mod.rpartition(".")[0]
        tree = ast.parse(path.read_text(encoding="utf-8"))
        top = {id(n) for n in tree.body}
        out = []
        for node in ast.walk(tree):
            targets = []
            if isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    anchor = pkg.split(".")[: len(pkg.split(".")) - node.level + 1]
                    base = ".".join(anchor + ([node.module] if node.module else []))
                targets = [_resolve(f"{base}.{a.name}") for a in node.names]
            elif isinstance(node, ast.Import):
                targets = [_resolve(a.name) for a in node.names]
            out += [(t, id(node) in top) for t in targets if t.split(".")[0] == "adhfit" and t != mod]
        graph[mod] = out
    return graph


def _layer(mod: str) -> int | None:
    for prefix, layer in sorted(LAYERS, key=lambda p: -len(p[0])):
        if mod == prefix or mod.startswith(prefix + "."):
            return layer
    return None


GRAPH = _imports()


def test_every_module_has_a_layer():
    assert [m for m in GRAPH if m != "adhfit" and _layer(m) is None] == []


def test_imports_run_one_way():
    upward, hooks = [], set()
    for mod, imports in GRAPH.items():
        if mod == "adhfit":  # the package's facade re-exports the public names (lazily)
            continue
        for target, at_top in imports:
            if target == "adhfit":  # ``from .. import __version__``
                continue
            if _layer(target) > _layer(mod):
                if (mod, target) in LAZY_HOOKS and not at_top:
                    hooks.add((mod, target))
                else:
                    upward.append(f"{mod} -> {target}" + (" (module level)" if at_top else ""))
    assert upward == []
    assert hooks == LAZY_HOOKS, "a presentation hook listed in LAZY_HOOKS is gone: remove it from the list"


def test_no_import_cycles():
    edges = {m: {t for t, _ in imps if t != "adhfit"} for m, imps in GRAPH.items()}
    index, low, stack, on, cycles = {}, {}, [], set(), []

    def visit(v):  # Tarjan's strongly connected components
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in edges.get(v, ()):
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
                cycles.append(sorted(comp))

    for v in list(edges):
        if v not in index:
            visit(v)
    # a package's __init__ importing its own submodules is not a cycle of the design
    cycles = [c for c in cycles if not all(m.startswith(c[0] + ".") or m == c[0] for m in c)]
    assert cycles == []


def _calls(path: Path):
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Call):
            f = node.func
            if isinstance(f, ast.Name) and f.id == "print":
                yield node.lineno, "print"
            elif isinstance(f, ast.Attribute) and f.attr == "write" and isinstance(f.value, ast.Attribute) \
                    and f.value.attr in ("stdout", "stderr"):
                yield node.lineno, f"sys.{f.value.attr}.write"


def test_only_the_command_line_prints():
    found = [f"{p.relative_to(PACKAGE.parent)}:{line} {what}" for p in sorted(PACKAGE.rglob("*.py"))
             if _module(p).split(".")[:2] != ["adhfit", "cli"] for line, what in _calls(p)]
    assert found == []


def test_one_engine():
    """The large-stretch physics is compiled once, in adhfit/core (no numpy twin, no backend switch);
    the exact membrane's kernels live in adhfit/exact.  Nothing else defines kernels."""
    assert not (PACKAGE / "core" / "compiled.py").exists() and not (PACKAGE / "core" / "backend.py").exists()
    kernels = set()
    for path in sorted(PACKAGE.rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        assert "ADHFIT_BACKEND" not in text, path
        for node in ast.walk(ast.parse(text)):
            names = [ast.unparse(d) for d in getattr(node, "decorator_list", [])]
            if isinstance(node, ast.FunctionDef) and any(n.split("(")[0].split(".")[-1] in ("jit", "njit")
                                                         for n in names):
                kernels.add(_module(path).split(".")[1])
            if isinstance(node, (ast.Import, ast.ImportFrom)) and "numba" in ast.unparse(node).split()[1]:
                kernels.add(_module(path).split(".")[1])
    assert kernels == {"core", "exact"}
    loading = {t for t, _ in GRAPH["adhfit.loading"]}
    assert {t.split(".")[1] for t in loading} <= {"core", "errors", "params", "histories"}


@pytest.mark.parametrize("module", ["adhfit.fitting.api", "adhfit.fitting.stage", "adhfit.fitting.bayes.sampling"])
def test_fitting_does_not_reach_the_report_or_the_command_line(module):
    """The fitting modules the command line calls never import reports or the command line (at any depth)."""
    seen, todo = set(), [module]
    while todo:
        m = todo.pop()
        if m in seen:
            continue
        seen.add(m)
        todo += [t for t, _ in GRAPH.get(m, []) if t != "adhfit" and (m, t) not in LAZY_HOOKS]
    assert not [m for m in seen if _layer(m) > 5]


def test_one_fit_path_no_twins_and_no_private_reach():
    """A curve is a series of one: fitting/ and report/ hold no ``global_*`` / ``series*`` twin modules, and
    no module of the package imports another module's private name (``from .x import _y``)."""
    import ast
    root = Path(__file__).resolve().parents[1] / "adhfit"
    twins = [p.name for p in (root / "fitting").glob("*.py")
             if p.stem.startswith(("global_", "series")) or p.stem.endswith("_mcmc") or p.stem.startswith("mcmc_")]
    assert not twins
    private = []
    for path in root.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom):
                private += [f"{path.relative_to(root)}: {a.name}" for a in node.names
                            if a.name.startswith("_") and not a.name.startswith("__")]
    assert not private, private
    # issue 19: "at most ~20 modules"; the MCMC modules live in their own sub-package (fitting/bayes/)
    assert len(list((root / "fitting").glob("*.py"))) <= 20
    assert len(list((root / "fitting" / "bayes").glob("*.py"))) <= 6


def test_report_has_one_writer_per_format():
    """Issue 19 item 3: every report reads one report dict; one writer per format, no per-series or per-method
    twins (``series_*``, ``*_mcmc``, ``mcmc_markdown``), and the writers know blocks, not report keys."""
    names = {p.stem for p in (PACKAGE / "report").glob("*.py")}
    assert not [n for n in names if n.startswith("series") or n.endswith("_mcmc") or n.startswith("mcmc_markdown")]
    assert {"view", "sections", "json_report", "markdown", "html"} <= names
    for writer in ("markdown", "html"):
        tree = ast.parse((PACKAGE / "report" / f"{writer}.py").read_text(encoding="utf-8"))
        keys = {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and n.value in
                ("curves", "mcmc", "sampling", "segments", "fits")}
        assert keys == set(), f"{writer}.py reads report keys {keys}: build the section in sections.py"
    private = [f"{path.name}: {a.name}" for path in (PACKAGE / "report").glob("*.py")
               for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))) if isinstance(node, ast.ImportFrom)
               for a in node.names if a.name.startswith("_") and not a.name.startswith("__")]
    assert private == [], "report/ imports another module's private name"


def test_report_files_are_written_through_one_atomic_helper():
    """Issue 23 item 6: no report module writes a file directly (write_text, write_bytes, open(..., "w"),
    savefig to a path); they call adhfit.report.files, which writes a temporary file and renames it."""
    found = []
    for path in sorted((PACKAGE / "report").glob("*.py")):
        if path.name == "files.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) \
                    and node.func.attr in ("write_text", "write_bytes"):
                found.append(f"{path.name}:{node.lineno} {node.func.attr}")
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "open":
                found.append(f"{path.name}:{node.lineno} open")
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "savefig" \
                    and not any(isinstance(k.value, ast.Constant) and k.arg == "format" for k in node.keywords):
                found.append(f"{path.name}:{node.lineno} savefig without a stream")
    assert found == []
