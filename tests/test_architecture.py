"""The package's shape: no import cycles, lower layers never import upper ones, and it runs without Numba or MKL.

The import graph is read from the source (``ast``), function-level and ``TYPE_CHECKING`` imports included:
a cycle through a lazy import is still a cycle in the design.
"""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import cvxgeodesic  # noqa: E402

# the package that is imported: src/cvxgeodesic in a checkout (editable install), site-packages for a wheel
PACKAGE = Path(cvxgeodesic.__file__).resolve().parent

#: Layers from the bottom up (docs/architecture.md); a module belongs to the layer of its longest matching
#: prefix. A module may import its own layer and the layers below it.
LAYERS: list[tuple[str, tuple[str, ...]]] = [
    ("leaf", ("errors", "_atomic", "_threads", "_cluster", "_jit", "_signals", "validation", "results", "tables",
              "capabilities", "_checkpoint")),
    # the file formats know nothing of TriMesh or of each other's callers: load_mesh, io and the CLI use them
    ("mesh formats", ("mesh.formats",)),
    ("mesh", ("mesh",)),
    # the user's source types and their resolution against a mesh
    ("sources", ("sources",)),
    ("linalg", ("linalg",)),
    ("operators", ("operators",)),
    # the conic program: the one shape the builders make and the solvers take
    ("program", ("problems.conic",)),
    ("solvers", ("solvers",)),
    # the builders and the source rows make a program and call no solver: above the solvers, which never import them
    ("problems", ("problems",)),
    ("baselines", ("baselines",)),
    ("api", ("api", "rows", "strategies", "paths", "_verbose")),
    ("evaluation/pictures", ("evaluation", "plotting", "viewer")),
    ("applications", ("cli", "compare", "batch", "demo", "__main__",
                      "")),  # "": the package __init__
]

#: Upward imports that are known and accepted, as (importing module, imported module or package prefix): why.
EXCEPTIONS: dict[tuple[str, str], str] = {
    # the thread policy bounds the pools of the compiled kernels (solver layer) and of MKL (linalg), and is
    # applied by every layer that runs a pool, so it sits at the bottom and imports those two lazily
    ("_threads", "solvers"): "thread limits of the Numba kernels",
    ("_threads", "linalg"): "thread limits of PARDISO",
}


def _modules() -> dict[str, tuple[Path, bool]]:
    """Dotted names (without the ``cvxgeodesic.`` prefix; ``""`` for the package) → (path, is_package)."""
    out = {}
    for path in PACKAGE.rglob("*.py"):
        parts = list(path.relative_to(PACKAGE).with_suffix("").parts)
        is_pkg = parts[-1] == "__init__"
        if is_pkg:
            parts = parts[:-1]
        out[".".join(parts)] = (path, is_pkg)
    return out


def _targets(module: str, is_pkg: bool, node: ast.Import | ast.ImportFrom, known: set[str]) -> list[str]:
    """The package modules an import statement of ``module`` loads (by name, relative imports resolved)."""
    full = ["cvxgeodesic", *module.split(".")] if module else ["cvxgeodesic"]
    names: list[str] = []
    if isinstance(node, ast.Import):
        names = [a.name for a in node.names]
    else:
        if node.level:
            base = full if is_pkg else full[:-1]
            base = base[: len(base) - (node.level - 1)]
            target = ".".join(base + ([node.module] if node.module else []))
        else:
            target = node.module or ""
        # "from pkg import sub" loads the submodule pkg.sub; "from mod import name" loads mod
        names = [f"{target}.{a.name}" if f"{target}.{a.name}".removeprefix("cvxgeodesic.") in known else target
                 for a in node.names]
    out = []
    for name in names:
        if name == "cvxgeodesic" or name.startswith("cvxgeodesic."):
            short = name.removeprefix("cvxgeodesic").removeprefix(".")
            if short in known:
                out.append(short)
    return out


def import_graph() -> dict[str, set[str]]:
    """Module → the package modules it imports anywhere in its source (itself excluded)."""
    mods = _modules()
    known = set(mods)
    graph: dict[str, set[str]] = {}
    for mod, (path, is_pkg) in mods.items():
        deps: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import | ast.ImportFrom):
                deps.update(_targets(mod, is_pkg, node, known))
        deps.discard(mod)
        graph[mod] = deps
    return graph


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import cycle as ``[a, b, ..., a]``, or None (iterative depth-first search)."""
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    for root in sorted(graph):
        if state.get(root):
            continue
        path, stack = [root], [iter(sorted(graph[root]))]
        state[root] = 1
        while stack:
            nxt = next(stack[-1], None)
            if nxt is None:
                state[path.pop()] = 2
                stack.pop()
            elif state.get(nxt) == 1:
                return path[path.index(nxt):] + [nxt]
            elif not state.get(nxt):
                state[nxt] = 1
                path.append(nxt)
                stack.append(iter(sorted(graph[nxt])))
    return None


def layer_of(module: str) -> int:
    """Index in :data:`LAYERS` of the longest prefix matching ``module``."""
    best, best_len = -1, -1
    for i, (_, prefixes) in enumerate(LAYERS):
        for p in prefixes:
            hit = module == p or (p and module.startswith(p + ".")) or (p == "" and module == "")
            if hit and len(p) > best_len:
                best, best_len = i, len(p)
    if best < 0:
        raise AssertionError(f"module cvxgeodesic.{module} is in no layer: add it to LAYERS in {__file__}")
    return best


def _excepted(src: str, dst: str) -> tuple[str, str] | None:
    for key in EXCEPTIONS:
        a, b = key
        if src == a and (dst == b or dst.startswith(b + ".")):
            return key
    return None


def upward_imports(graph: dict[str, set[str]]) -> tuple[list[str], set[tuple[str, str]]]:
    """Imports of a higher layer not in :data:`EXCEPTIONS` (as messages), and the exceptions that were used."""
    bad, used = [], set()
    for src, deps in sorted(graph.items()):
        for dst in sorted(deps):
            ls, ld = layer_of(src), layer_of(dst)
            if ld > ls:
                key = _excepted(src, dst)
                if key is None:
                    bad.append(f"cvxgeodesic.{src} ({LAYERS[ls][0]}) imports cvxgeodesic.{dst} ({LAYERS[ld][0]})")
                else:
                    used.add(key)
    return bad, used


def test_the_import_graph_is_read():
    g = import_graph()
    # a top-level, a relative function-level and a "from . import submodule" import
    assert "validation" in g["api"] and "strategies" in g["api"]
    assert "problems.squared_distance" in g["strategies.order2"]
    assert "_threads" in g[""]
    assert "linalg.pardiso" in g["_threads"]


def test_no_import_cycles():
    cycle = find_cycle(import_graph())
    assert cycle is None, "import cycle: " + " -> ".join(f"cvxgeodesic.{m}".rstrip(".") for m in cycle)


def test_find_cycle_sees_a_cycle():
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": set()}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None


def test_lower_layers_never_import_upper_ones():
    bad, used = upward_imports(import_graph())
    assert not bad, "upward imports:\n" + "\n".join(bad)
    stale = sorted(set(EXCEPTIONS) - used)
    assert not stale, f"EXCEPTIONS lists imports that no longer exist, remove them: {stale}"


def test_the_only_accepted_upward_imports_are_the_thread_limits():
    # issue 42: the solver's warm-up imported the problem builders from above it; now nothing but the thread policy
    # reaches up a layer
    others = sorted(key for key in EXCEPTIONS if key[0] != "_threads")
    assert not others, f"accepted upward imports besides the thread limits: {others}"


# ---------------------------------------------------------------------------------------------------------------
# issue 42's counts (tools/architecture_counts.py): the dimension is the mesh's type, not an integer in shared code
# ---------------------------------------------------------------------------------------------------------------
COUNTS_TOOL = Path(__file__).resolve().parents[1] / "tools" / "architecture_counts.py"
#: Targets of issue 42: at most this many dimension branches outside mesh/, each with a ``# dimension:`` reason.
MAX_DIMENSION_BRANCHES = 5


def _counting_tool():
    import importlib.util

    if not COUNTS_TOOL.exists():
        pytest.skip(f"{COUNTS_TOOL} is not in this checkout (an installed wheel)")
    spec = importlib.util.spec_from_file_location("architecture_counts", COUNTS_TOOL)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # the dataclass in it looks its module up
    spec.loader.exec_module(module)
    return module


def _places(places: list[str]) -> str:
    return "\n".join(f"  src/cvxgeodesic/{p}" for p in places)


def test_the_counting_tool_sees_what_it_counts(tmp_path):
    tool = _counting_tool()
    (tmp_path / "mesh").mkdir()
    (tmp_path / "mesh" / "own.py").write_text("def f(m):\n    return m.dim == 2\n")  # the mesh classes may branch
    (tmp_path / "shared.py").write_text(
        "from typing import Any\n"
        "def f(mesh: Any, dim):\n"
        "    if mesh.dim == 3:\n"
        "        return {2: 'a', 3: 'b'}\n"
        "    return dim in (2, 3)  # dimension: a reason\n")
    c = tool.counts(tmp_path)
    assert c.branches == ["shared.py:3"] and c.branches_with_reason == ["shared.py:5"]
    assert c.dim_tables == ["shared.py:4"] and c.mesh_any == ["shared.py:2"]


def test_dimension_branches_outside_mesh_are_few_and_give_their_reason():
    c = _counting_tool().counts(PACKAGE)
    assert not c.branches, (f"{len(c.branches)} dimension branches outside mesh/ without a '# dimension: <reason>' "
                            f"comment (ask mesh.reference instead):\n{_places(c.branches)}")
    assert len(c.branches_with_reason) <= MAX_DIMENSION_BRANCHES, (
        f"{len(c.branches_with_reason)} dimension branches with a reason, more than {MAX_DIMENSION_BRANCHES}:\n"
        f"{_places(c.branches_with_reason)}")


def test_no_table_is_keyed_by_the_dimension():
    c = _counting_tool().counts(PACKAGE)
    assert not c.dim_tables, f"{len(c.dim_tables)} dicts keyed by 2 and 3:\n{_places(c.dim_tables)}"


def test_no_mesh_parameter_is_typed_any():
    c = _counting_tool().counts(PACKAGE)
    assert not c.mesh_any, f"{len(c.mesh_any)} parameters 'mesh: Any':\n{_places(c.mesh_any)}"


#: Modules that issue 42 has already rid of dimension branches and tables: they stay so.
DIMENSION_FREE = ("sources.py", "problems/source_rows.py", "problems/conic.py", "strategies/warm_up.py",
                  "solvers/ipm/solver.py")


def test_the_modules_made_dimension_free_stay_so():
    c = _counting_tool().counts(PACKAGE)
    places = [p for p in c.branches + c.branches_with_reason + c.dim_tables if p.rsplit(":", 1)[0] in DIMENSION_FREE]
    assert not places, f"dimension branches or tables in {DIMENSION_FREE}:\n{_places(places)}"


#: No module of the package is longer than this (a module that grows past it holds more than one topic).
MAX_MODULE_LINES = 900


def test_no_module_is_longer_than_the_limit():
    long = {name: n for name, (path, _) in _modules().items()
            if (n := len(path.read_text(encoding="utf-8").splitlines())) > MAX_MODULE_LINES}
    assert not long, long


def test_every_module_has_a_layer():
    for mod in import_graph():
        layer_of(mod)


# The blocker: numba and mkl cannot be imported and libmkl_rt cannot be loaded (so our PARDISO binding finds no MKL).
_BLOCKER = r"""
import ctypes, importlib.abc, sys
BLOCKED = ("numba", "mkl", "pypardiso")
class Blocker(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if any(name == b or name.startswith(b + ".") for b in BLOCKED):
            raise ImportError(f"{name} is blocked by the test")
        return None
sys.meta_path.insert(0, Blocker())
_cdll = ctypes.CDLL.__init__
def _no_mkl(self, name, *args, **kwargs):
    if name and "mkl" in str(name):
        raise OSError(f"{name}: blocked by the test")
    _cdll(self, name, *args, **kwargs)
ctypes.CDLL.__init__ = _no_mkl
"""

_SOLVE = r"""
import json
import numpy as np
import cvxgeodesic as cg
for mod in ("numba", "mkl"):
    assert mod not in sys.modules, mod
res = cg.GeodesicSolver(cg.icosphere(2)).solve(0)
np.save(sys.argv[1], res.distance)
print(json.dumps({"solver": res.info.solver, "notes": res.info.notes, "status": res.info.status,
                  "backend": cg.GeodesicSolver(cg.icosphere(2)).solver_name}))
"""


def _run(code: str, out: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(PACKAGE.parent) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    return subprocess.run([sys.executable, "-c", code, str(out)], capture_output=True, text=True, env=env,
                          timeout=300)


def test_the_blocker_blocks(tmp_path):
    # without this the test below could pass because nothing was blocked
    code = _BLOCKER + r"""
import ctypes
for name in ("numba", "mkl"):
    try:
        __import__(name)
    except ImportError:
        pass
    else:
        raise SystemExit(f"{name} was imported")
try:
    ctypes.CDLL("libmkl_rt.so.2")
except OSError:
    pass
else:
    raise SystemExit("libmkl_rt was loaded")
from cvxgeodesic.linalg import pardiso_available
if pardiso_available():  # our ctypes binding imports, but finds no MKL to load
    raise SystemExit("PARDISO is available")
print("blocked")
"""
    proc = _run(code, tmp_path / "x")
    assert proc.returncode == 0 and "blocked" in proc.stdout, proc.stdout + proc.stderr


def test_imports_and_solves_with_clarabel_without_numba_and_mkl(tmp_path):
    import cvxgeodesic as cg

    out = tmp_path / "d.npy"
    proc = _run(_BLOCKER + _SOLVE, out)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    import json

    info = json.loads(proc.stdout.strip().splitlines()[-1])
    assert info["solver"] == "clarabel" and info["backend"] == "clarabel" and info["status"] == "optimal"
    assert any("Clarabel" in n and "interior-point" in n and "not available" in n for n in info["notes"]), info
    mesh = cg.icosphere(2)
    # the optimum to a tighter tolerance: at tol = 1e-8 Clarabel's field and the interior-point solver's are each
    # up to 8e-7 of the diagonal from it (measured 2026-12-01), on opposite sides; 1.23e-6 for Clarabel's since the
    # bounds d >= 0 next to the source (active there) are part of the smoothed program (2026-12-02; Clarabel at
    # 1e-11: 7.9e-8)
    ref = cg.GeodesicSolver(mesh, tol=1e-11).solve(0).distance
    np.testing.assert_allclose(np.load(out), ref, atol=2e-6 * mesh.bbox_diagonal)
