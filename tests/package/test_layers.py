"""The layer rules of the package, checked on its import graph (see docs/architecture.md).

Every ``src/imdrive/**/*.py`` is parsed with :mod:`ast`; every ``import`` and ``from ... import``
anywhere in a file (module level, inside functions, under ``if TYPE_CHECKING``) and every
``importlib.import_module("imdrive...")`` with a literal name is an edge of the graph. The
rules are written against layers, not file lists, so modules added later are checked too.

Ranks
-----
A module belongs to the layer of its first name under ``imdrive`` (``imdrive.run.build`` ->
``run``) and may import modules of its own rank or lower, never higher:

==== ============================================ ===============================================
rank layer                                        why it sits there
==== ============================================ ===============================================
     ``_progress``, ``_deprecated``, ``_figure``  nothing of imdrive above rank 0
1    ``config``, ``design``                       what a run *is* (machine, inverter, profiles,
                                                  scenario, presets) and the gain formulas an
                                                  estimator's settings design its gains with:
                                                  pure Python, never numba, so reading a
                                                  scenario costs no compilation
2    ``kernels``                                  compiled blocks on named records; they import
                                                  only rank 0 and ``kernels`` (they never see a
                                                  Python object, so never ``config`` either)
4    ``fuzzy``, ``analysis``                      offline theory: Table III from rules (with the
                                                  compiled loops of ``kernels.fuzzy``) and the
                                                  steady state (numba-free, over
                                                  ``config.machine``)
5    ``run``                                      assembles a drive: config + design + fuzzy ->
                                                  records -> kernels -> result, its metrics and
                                                  figures (``run.plots``)
6    ``sweep``, ``studies``, ``commission``       users of ``run``: many runs, the paper's
                                                  studies, the identification run
7    ``cli``, ``__main__``                        the command line, on top of everything
==== ============================================ ===============================================

``config`` and ``kernels`` never import each other (the run layer translates one into the
other), and ``config`` and ``analysis`` never load numba, not even through what they import.

Exempt: ``imdrive/__init__.py`` (an alias of other modules: its own imports are not checked).
The 0.1 import paths (``imdrive.scenario``, ``imdrive.simulate``, ...) have no file: the one
compatibility module :mod:`imdrive._deprecated` builds them on import from the modules
:data:`~imdrive._deprecated.OLD_PATHS` names (read here from its source); package code must not
import an old path. Importing the root ``imdrive`` (for ``__version__``) counts as importing the
highest layer the root itself imports.

Depth
-----
The longest chain of imports between imdrive modules is measured twice: in modules, and in
levels, i.e. in the ranks it passes through (consecutive modules of one rank count once). The
levels must stay within :data:`MAX_LEVELS` ("at most 6 import levels"); the module
count is printed for information (inside a layer, a chain of small modules is no cost).

Known violations
----------------
Violations that exist in code whose owner has not fixed them yet are listed in
:data:`KNOWN_VIOLATIONS`, each with the reason; they are tolerated, anything new fails, and an
entry that no longer occurs fails too, so the list can only shrink.
"""

from __future__ import annotations

import ast
import importlib
import os
import pkgutil
import shutil
import subprocess
import sys
import textwrap
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[2] / "src"
PKG = SRC / "imdrive"

RANK = {
    "errors": 0,
    "_cache": 0,
    "_compiling": 0,
    "_io": 0,
    "_progress": 0,
    "_deprecated": 0,
    "_figure": 0,
    "config": 1,
    "kernels": 2,
    "design": 1,
    "fuzzy": 4,
    "analysis": 4,
    "run": 5,
    "sweep": 6,
    "studies": 6,
    "stability": 6,
    "bench": 6,
    "commission": 6,
    "cli": 7,
    "__main__": 7,
}
BASE = {layer for layer, rank in RANK.items() if rank == 0}

#: layers restricted beyond their rank: they may import only these layers
ONLY = {"kernels": BASE | {"kernels"}}

#: layers that must not load numba, directly or through anything they import
NUMBA_FREE = ("config", "design", "analysis")

#: where ``import numba`` may appear: the kernels and the cache folder they compile into
NUMBA_ALLOWED = ("kernels", "_cache", "_compiling")  # _compiling: numba's compile events

#: order inside a package: a module may import only siblings listed before it
INTRA = {
    "fuzzy": ("tables", "inference", "fit"),
    "analysis": (
        "circuit",
        "foc",
        "drive_steady_state",
        "figures",
        "inertia",
        "nameplate_lee",
        "nameplate_catalogue",
        "nameplate_fit",
        "nameplate",
        "nameplate_cli",
        "circuit_from_tests",
        "commissioning",
        "headroom",
        "observability",
    ),
}

MAX_LEVELS = 6

#: (rule, importer, imported) -> why it is tolerated for now. Rules: "rank", "only", "shim",
#: "numba", "intra", "cycle" (imported = the module the cut edge points to).
KNOWN_VIOLATIONS: dict = {}  # none left: the last cycle (config.scenario <-> overrides) is gone


# --------------------------------------------------------------------------------------------
# the import graph


@dataclass(frozen=True)
class Edge:
    importer: str
    target: str  # an imdrive module, or the top-level name of an outside package
    path: Path
    line: int
    toplevel: bool  # executed at import time (not inside a function)

    @property
    def where(self) -> str:
        return f"{self.path.relative_to(SRC.parent)}:{self.line}"


def _old_paths() -> frozenset[str]:
    # the keys of imdrive._deprecated.OLD_PATHS, read from the source (nothing imported)
    tree = ast.parse((PKG / "_deprecated.py").read_text(encoding="utf-8"))
    for node in tree.body:
        target = getattr(node, "target", None) or (getattr(node, "targets", None) or [None])[0]
        if isinstance(target, ast.Name) and target.id == "OLD_PATHS":
            return frozenset(ast.literal_eval(node.value))
    raise AssertionError("imdrive/_deprecated.py defines no OLD_PATHS")


OLD_PATHS = _old_paths()


def _module_name(path: Path) -> tuple[str, bool]:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    is_pkg = parts[-1] == "__init__"
    return ".".join(parts[:-1] if is_pkg else parts), is_pkg


class _Collector(ast.NodeVisitor):
    def __init__(self, name: str, is_pkg: bool, path: Path, modules):
        self.name, self.path, self.modules = name, path, modules
        self.package = name if is_pkg else name.rpartition(".")[0]
        self.depth = 0
        self.edges: list[Edge] = []

    def _add(self, target: str, node) -> None:
        if not target.startswith("imdrive"):
            target = target.split(".")[0]
        elif target not in self.modules and target not in OLD_PATHS:
            # e.g. a name misspelt; keep the closest module
            while target not in self.modules and "." in target:
                target = target.rpartition(".")[0]
        edge = Edge(self.name, target, self.path, node.lineno, self.depth == 0)
        if edge not in self.edges:  # `from m import a, b` is one edge
            self.edges.append(edge)

    def _scoped(self, node):
        self.depth += 1
        self.generic_visit(node)
        self.depth -= 1

    visit_FunctionDef = visit_AsyncFunctionDef = visit_Lambda = _scoped

    def visit_Import(self, node):
        for alias in node.names:
            self._add(alias.name, node)

    def visit_ImportFrom(self, node):
        base = node.module or ""
        if node.level:
            parts = self.package.split(".")
            parts = parts[: len(parts) - node.level + 1]
            base = ".".join(parts + ([node.module] if node.module else []))
        for alias in node.names:
            sub = f"{base}.{alias.name}"
            self._add(sub if sub in self.modules or sub in OLD_PATHS else base, node)

    def visit_Call(self, node):
        f = node.func
        name = f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", "")
        if (
            name == "import_module"
            and node.args
            and isinstance(node.args[0], ast.Constant)
            and isinstance(node.args[0].value, str)
        ):
            self._add(node.args[0].value, node)
        self.generic_visit(node)


@dataclass(frozen=True)
class Graph:
    modules: dict[str, Path]
    edges: tuple[Edge, ...]

    def out(self, name: str) -> list[Edge]:
        return [e for e in self.edges if e.importer == name]

    def internal(self, name: str) -> set[str]:
        return {e.target for e in self.out(name) if e.target in self.modules}


@cache
def graph() -> Graph:
    paths = sorted(PKG.rglob("*.py"))
    modules = {}
    for p in paths:
        name, _ = _module_name(p)
        modules[name] = p
    edges = []
    for name, p in modules.items():
        tree = ast.parse(p.read_text(encoding="utf-8"), filename=str(p))
        col = _Collector(name, p.name == "__init__.py", p, modules)
        col.visit(tree)
        edges += col.edges
    return Graph(modules, tuple(edges))


def layer(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else None  # None: the root package


def exempt(module: str) -> bool:
    return module == "imdrive"


@cache
def rank(module: str) -> int:
    if module == "imdrive":  # the root counts as the highest layer it imports itself
        return max((rank(t) for t in graph().internal("imdrive")), default=0)
    return RANK[layer(module)]


def _report(found, rule_name: str) -> str:
    lines = [f"{len(found)} violation(s) of the rule '{rule_name}':"]
    lines += [f"  {e.where}: {e.importer} imports {e.target}  ({why})" for e, why in found]
    return "\n".join(lines)


def _new(found):
    return [(e, why) for e, why in found if (why.split(":")[0], e.importer, e.target) not in KNOWN]


KNOWN = set(KNOWN_VIOLATIONS)


# --------------------------------------------------------------------------------------------
# rules


def rank_violations():
    g = graph()
    found = []
    for e in g.edges:
        if exempt(e.importer):
            continue
        if e.target in OLD_PATHS:
            found.append((e, "shim: package code imports a deprecated 0.1 import path"))
            continue
        if e.target not in g.modules:
            continue
        src, dst = layer(e.importer), layer(e.target)
        if src in ONLY and dst not in ONLY[src]:
            found.append((e, f"only: {src} may import only {sorted(ONLY[src])}"))
        elif rank(e.target) > rank(e.importer):
            up = f"rank: {src} (rank {rank(e.importer)}) imports rank {rank(e.target)}"
            found.append((e, up))
    return found


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_every_module_has_a_layer():
    missing = sorted({layer(m) for m in graph().modules if layer(m) and layer(m) not in RANK})
    assert not missing, f"give these a rank in RANK of tests/package/test_layers.py: {missing}"


def test_old_paths_are_detected():
    # the old 0.1 paths (imdrive.scenario, imdrive.simulate, ...) come from OLD_PATHS and have
    # no file of their own; a silent change of _deprecated must not turn the shim rule off
    assert {"imdrive.scenario", "imdrive.simulate", "imdrive.engine"} <= OLD_PATHS
    assert not OLD_PATHS & set(graph().modules), "an old path has a file again"
    assert "imdrive.cli" not in OLD_PATHS


def test_no_layer_imports_upward():
    found = _new(rank_violations())
    assert not found, _report(found, "imports go to the same or a lower layer only")


def test_numba_only_in_kernels_cache_and_compile_notice():
    found = [
        (e, "numba: numba imported outside kernels/, _cache.py and _compiling.py")
        for e in graph().edges
        if e.target == "numba" and not exempt(e.importer) and layer(e.importer) not in NUMBA_ALLOWED
    ]
    found = _new(found)
    assert not found, _report(
        found, "numba is imported only under kernels/ and by _cache.py and _compiling.py"
    )


def _closure(start: str) -> set[str]:
    # every imdrive module loaded when `start` is imported: its imports and, as Python does,
    # the __init__ of every package on the way
    g, seen, todo = graph(), set(), [start]
    while todo:
        m = todo.pop()
        if m in seen:
            continue
        seen.add(m)
        parts = m.split(".")
        todo += [".".join(parts[:i]) for i in range(1, len(parts))]
        todo += list(g.internal(m))
    return seen


@pytest.mark.parametrize("name", NUMBA_FREE)
def test_numba_free_layers_statically(name):
    g = graph()
    for module in [m for m in g.modules if layer(m) == name]:
        loaded = _closure(module)
        bad = sorted(
            f"{e.where}: {e.importer} imports {e.target}"
            for m in loaded
            for e in g.out(m)
            if e.target == "numba" or layer(e.target) == "kernels"
        )
        assert not bad, f"importing {module} would load numba through:\n  " + "\n  ".join(bad)


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_numba_free_layers_at_run_time():
    mods = [m for m in graph().modules if layer(m) in NUMBA_FREE]
    code = textwrap.dedent(f"""
        import importlib, sys
        for m in {mods!r}:
            importlib.import_module(m)
        bad = sorted(k for k in sys.modules if k == "numba" or k.startswith("imdrive.kernels"))
        print(" ".join(bad))
    """)
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == "", f"importing {NUMBA_FREE} loaded: {res.stdout}"


def test_order_inside_packages():
    g = graph()
    found = []
    for pkg, order in INTRA.items():
        names = [f"imdrive.{pkg}.{m}" for m in order]
        for i, importer in enumerate(names):
            for e in g.out(importer):
                if e.target in names[i:]:
                    found.append((e, f"intra: imdrive.{pkg} is ordered {' <- '.join(order)}"))
        extra = {m for m in g.modules if m.startswith(f"imdrive.{pkg}.")} - set(names)
        assert not extra, f"add {sorted(extra)} to INTRA['{pkg}'] in tests/package/test_layers.py"
    found = _new(found)
    assert not found, _report(found, "a package's modules import only earlier siblings")


# --------------------------------------------------------------------------------------------
# cycles and depth


def _cut_edges() -> set[tuple[str, str]]:
    return {(a, b) for rule, a, b in KNOWN if rule == "cycle"}


def _cycles(cut=frozenset()) -> list[list[str]]:
    # strongly connected components with more than one module (or a self-import), Tarjan
    g = graph()
    succ = {m: sorted(g.internal(m) - {b for a, b in cut if a == m}) for m in g.modules}
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in succ[v]:
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
            if len(comp) > 1 or v in succ[v]:
                out.append(sorted(comp))

    for v in sorted(g.modules):
        if v not in index:
            visit(v)
    return out


def test_no_import_cycles():
    cycles = _cycles(frozenset(_cut_edges()))
    detail = []
    for comp in cycles:
        detail.append(f" cycle through {', '.join(comp)}:")
        for m in comp:
            inside = [e for e in graph().out(m) if e.target in comp]
            detail += [f"  {e.where}: {m} imports {e.target}" for e in inside]
    assert not cycles, "import cycles between imdrive modules:\n" + "\n".join(detail)


def test_known_cycles_are_real():
    # each cut edge must be part of a cycle today, or it should leave KNOWN_VIOLATIONS
    every = [set(c) for c in _cycles()]
    stale = [(a, b) for a, b in _cut_edges() if not any({a, b} <= c for c in every)]
    assert not stale, f"no longer cycles, remove from KNOWN_VIOLATIONS: {stale}"


def longest_chains() -> tuple[list[str], list[str]]:
    """The longest import chain in modules, and the one passing through the most ranks."""
    g = graph()
    cut = _cut_edges()
    nodes = [m for m in g.modules if not exempt(m)]
    succ = {}
    for m in nodes:
        succ[m] = [t for t in sorted(g.internal(m)) if not exempt(t) and (m, t) not in cut]

    @cache
    def by_modules(m):
        best = (m,)
        for t in succ[m]:
            c = (m, *by_modules(t))
            if len(c) > len(best):
                best = c
        return best

    @cache
    def by_levels(m):
        best, best_n = (m,), 1
        for t in succ[m]:
            c, n = by_levels(t)
            n += rank(m) != rank(t)
            if n > best_n:
                best, best_n = (m, *c), n
        return best, best_n

    modules = max((by_modules(m) for m in nodes), key=len)
    levels = max((by_levels(m) for m in nodes), key=lambda cn: cn[1])[0]
    return list(modules), list(levels)


def _levels(chain: list[str]) -> int:
    return 1 + sum(rank(a) != rank(b) for a, b in zip(chain, chain[1:], strict=False))


def test_import_chains_are_shallow():
    if _cycles(frozenset(_cut_edges())):
        pytest.fail(
            "the depth is undefined while there are import cycles: see test_no_import_cycles"
        )
    modules, levels = longest_chains()
    msg = (
        f"longest chain in modules ({len(modules)}, for information):\n  "
        + " -> ".join(modules)
        + f"\nlongest chain in levels ({_levels(levels)}, at most {MAX_LEVELS}):\n  "
        + " -> ".join(f"{m} [{rank(m)}]" for m in levels)
    )
    print(msg)
    assert _levels(levels) <= MAX_LEVELS, msg


def test_known_violations_still_occur():
    # an entry whose import is gone must leave the list, so the list only shrinks
    g = graph()
    occurring = {(why.split(":")[0], e.importer, e.target) for e, why in rank_violations()}
    occurring |= {("numba", e.importer, "numba") for e in g.edges if e.target == "numba"}
    occurring |= {("cycle", a, b) for a, b in _cut_edges() if b in g.internal(a)}
    stale = sorted(KNOWN - occurring)
    assert not stale, (
        f"fixed, remove from KNOWN_VIOLATIONS in tests/package/test_layers.py: {stale}"
    )


# --------------------------------------------------------------------------------------------
# every kernel compiles into the hashed cache folder


def _dispatchers():
    import numba.core.dispatcher

    import imdrive.kernels

    found = []
    for info in pkgutil.walk_packages(imdrive.kernels.__path__, "imdrive.kernels."):
        mod = importlib.import_module(info.name)
        for name, obj in vars(mod).items():
            if (
                isinstance(obj, numba.core.dispatcher.Dispatcher)
                and obj.py_func.__module__ == mod.__name__
            ):
                found.append((f"{mod.__name__}.{name}", obj))
    return found


def test_every_cached_kernel_is_in_its_module_cache_folder():
    from numba.core.caching import NullCache

    from imdrive import _cache

    kernels = _dispatchers()
    cached = [(n, d) for n, d in kernels if not isinstance(d._cache, NullCache)]
    assert "imdrive.kernels.engine.run_drive" in dict(cached)  # the walk is not vacuous
    outside = [
        f"{n}: {d._cache._cache_path}"
        for n, d in cached
        if Path(d._cache._cache_path) != _cache.module_folder(d.py_func.__module__)
    ]
    assert not outside, "compiled outside their module's cache folder:\n  " + "\n  ".join(outside)


NEW_KERNEL = """
from numba import njit


@njit(cache=True)
def doubled(x):
    return 2.0 * x
"""


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_a_new_kernel_module_lands_in_its_cache_folder_without_registration(tmp_path):
    # a copy of the package with two modules nobody registered: one directly under kernels/,
    # one in a sub-package; imported directly, each must compile into its module's folder
    copy = tmp_path / "src" / "imdrive"
    shutil.copytree(PKG, copy, ignore=shutil.ignore_patterns("__pycache__"))
    (copy / "kernels" / "zz_new_block.py").write_text(NEW_KERNEL)
    (copy / "kernels" / "estimators" / "zz_new_estimator.py").write_text(NEW_KERNEL)
    cache_root = tmp_path / "cache"
    code = textwrap.dedent("""
        from pathlib import Path
        import imdrive.kernels.zz_new_block as a
        import imdrive.kernels.estimators.zz_new_estimator as b
        from imdrive import _cache

        folder = _cache.cache_root()
        for m in (a, b):
            assert Path(m.__file__).is_relative_to(Path.cwd()), m.__file__
            assert m.doubled(1.5) == 3.0
            where = Path(m.doubled._cache._cache_path)
            assert where == _cache.module_folder(m.__name__), f"{m.__name__} compiled into {where}"
        print(folder)
        print(sorted(p.name for p in folder.rglob("*.nbi")))
    """)
    env = {**os.environ, "PYTHONPATH": str(tmp_path / "src"), "IMDRIVE_CACHE_DIR": str(cache_root)}
    env.pop("NUMBA_CACHE_DIR", None)
    res = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True
    )
    assert res.returncode == 0, res.stderr
    folder_line, index_line = res.stdout.strip().splitlines()
    folder = Path(folder_line)
    assert folder == cache_root
    assert index_line.count("doubled") == 2  # one index file per new module, in its folder
    assert not list((tmp_path / "src").rglob("*.nbi"))  # nothing in the source tree
