"""Count what issue 42 counts: dimension branches, dimension-keyed tables, ``mesh: Any`` signatures.

Run from the repository root::

    python tools/architecture_counts.py            # the counts and every place counted
    python tools/architecture_counts.py --summary  # the counts only

What is counted, by reading the syntax trees of ``src/cvxgeodesic`` (not by grep, so a comment or a string never
counts):

- **dimension branches** outside ``mesh/``: a comparison of ``dim`` or ``x.dim`` with a number
  (``mesh.dim == 3``, ``dim in (2, 3)``), ``isinstance(x, TriMesh | TetMesh | CloudMesh)``, and ``x.is_volume``.
  A branch that stays gets a ``# dimension: <reason>`` comment on its line; those are listed as *with a reason*.
- **dimension-keyed tables**: dict literals whose keys are all the integers 2 and 3 (anywhere in the package).
- **``mesh: Any``**: a parameter named ``mesh`` (or ending in ``_mesh``) annotated ``Any``, in any function.
- **``MeshLike``** parameters, listed apart and not a target: the API edge's duck-typed input
  (:data:`cvxgeodesic.mesh.convert.MeshLike`, ``Any`` to a type checker), converted by ``as_mesh`` before use.

``tests/test_architecture.py`` asserts the targets of docs/architecture.md from :func:`counts`.
"""

from __future__ import annotations

import argparse
import ast
import sys
from dataclasses import dataclass, field
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "cvxgeodesic"
REASON = "# dimension:"
_MESH_CLASSES = {"TriMesh", "TetMesh", "CloudMesh"}


@dataclass
class Counts:
    """Places found, as ``"path:line"`` strings."""

    branches: list[str] = field(default_factory=list)
    branches_with_reason: list[str] = field(default_factory=list)
    dim_tables: list[str] = field(default_factory=list)
    mesh_any: list[str] = field(default_factory=list)
    mesh_like: list[str] = field(default_factory=list)


def _is_dim(node: ast.AST) -> bool:
    return (isinstance(node, ast.Name) and node.id == "dim") or (isinstance(node, ast.Attribute) and node.attr == "dim")


def _is_number(node: ast.AST) -> bool:
    if isinstance(node, ast.Constant) and isinstance(node.value, int) and not isinstance(node.value, bool):
        return True
    return isinstance(node, ast.Tuple | ast.List | ast.Set) and bool(node.elts) and all(map(_is_number, node.elts))


def _names(node: ast.AST) -> set[str]:
    return {n.id for n in ast.walk(node) if isinstance(n, ast.Name)} | {
        n.attr for n in ast.walk(node) if isinstance(n, ast.Attribute)}


def _branch(node: ast.AST) -> bool:
    if isinstance(node, ast.Compare):
        sides = [node.left, *node.comparators]
        return any(map(_is_dim, sides)) and any(map(_is_number, sides))
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "isinstance":
        return len(node.args) == 2 and bool(_names(node.args[1]) & _MESH_CLASSES)
    return isinstance(node, ast.Attribute) and node.attr == "is_volume"


def _dim_table(node: ast.AST) -> bool:
    if not isinstance(node, ast.Dict) or len(node.keys) < 2:
        return False
    keys = [k.value if isinstance(k, ast.Constant) else None for k in node.keys]
    return set(keys) <= {2, 3} and set(keys) == {2, 3}


def _mesh_params(node: ast.AST, annotations: set[str]) -> list[int]:
    if not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
        return []
    a = node.args
    params = [*a.posonlyargs, *a.args, *a.kwonlyargs, *(p for p in (a.vararg, a.kwarg) if p)]
    return [p.lineno for p in params if (p.arg == "mesh" or p.arg.endswith("_mesh")) and p.annotation is not None
            and ast.unparse(p.annotation) in annotations]


def counts(package: Path = PACKAGE) -> Counts:
    """Walk every module of the package and collect the places of each count."""
    out = Counts()
    for path in sorted(package.rglob("*.py")):
        rel = path.relative_to(package).as_posix()
        text = path.read_text()
        lines = text.splitlines()
        seen: set[int] = set()
        for node in ast.walk(ast.parse(text)):
            if _dim_table(node):
                out.dim_tables.append(f"{rel}:{node.lineno}")
            out.mesh_any += [f"{rel}:{ln}" for ln in _mesh_params(node, {"Any", "typing.Any"})]
            out.mesh_like += [f"{rel}:{ln}" for ln in _mesh_params(node, {"MeshLike"})]
            if rel.startswith("mesh/") or not _branch(node) or node.lineno in seen:
                continue
            seen.add(node.lineno)
            where = f"{rel}:{node.lineno}"
            (out.branches_with_reason if REASON in lines[node.lineno - 1] else out.branches).append(where)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--summary", action="store_true", help="print the counts only")
    args = ap.parse_args(argv)
    c = counts()
    for title, places in (("dimension branches outside mesh/ (no reason given)", c.branches),
                          ("dimension branches outside mesh/ with a '# dimension:' reason", c.branches_with_reason),
                          ("dimension-keyed tables ({2: ..., 3: ...})", c.dim_tables),
                          ("parameters 'mesh: Any'", c.mesh_any),
                          ("parameters 'mesh: MeshLike' (the API edge's duck-typed input; not a target)", c.mesh_like)):
        print(f"{len(places):4d}  {title}")
        if not args.summary:
            for p in places:
                print(f"        {p}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
