"""TetGen's ``.node`` / ``.ele`` pair: a tetrahedral mesh, read natively (no optional package).

Either file names the pair (the other has the same stem, in the same case). ``#`` comments and blank lines
are skipped, commas separate like spaces; the numbering is 0- or 1-based or anything else, as the ``.node``
file's point numbers say; attributes and boundary markers are ignored; 10-node tetrahedra are reduced to
their corners (noted).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...errors import MeshFormatError
from ._common import RawMesh, check_file

__all__ = ["read_mesh"]

#: TetGen's numbers (counts, point numbers) are stored as int64; larger ones cannot name anything in a file.
_INT_LIMIT = 2**63


def read_mesh(path: Path) -> RawMesh:
    """The points and tetrahedra of TetGen's pair, named after the common stem.

    Parameters
    ----------
    path : pathlib.Path
        The ``.node`` or the ``.ele`` file.

    Returns
    -------
    RawMesh
        ``V`` (n, 3) in the ``.node`` file's order, ``tets`` (k, 4) as 0-based indices into ``V`` (TetGen's
        numbering translated through the point numbers), no polygons.

    Raises
    ------
    MeshFormatError
        A missing or non-regular file, a malformed header or record (file and line named), a number beyond
        int64, fewer records than the header says, repeated point numbers, or an element naming an unknown point.
    """
    upper = path.suffix.isupper()
    node, ele = (path.with_suffix(ext.upper() if upper else ext) for ext in (".node", ".ele"))
    V, numbers = _read_node(node)
    tets, per = _read_ele(ele, node, numbers)
    notes = [f"{ele.name}: 10-node (quadratic) tetrahedra: their 4 corners are used"] if per == 10 else []
    empty = np.zeros(0, dtype=np.int64)
    return RawMesh(V, empty, empty, tets=tets, notes=notes, name=path.with_suffix("").name)


def _read_node(node: Path) -> tuple[np.ndarray, np.ndarray]:
    """The points (n, 3) of a ``.node`` file and their numbers (n,)."""
    recs = _records(node)
    ln, head = recs[0]
    h = _ints(node, ln, head[:4], "the header (points, dimension, attributes, markers)")
    if len(h) < 2 or h[0] < 1 or h[1] != 3:
        raise MeshFormatError(f"{node}, line {ln}: the header must be '<points> 3 [attributes] [markers]' with at "
                              f"least one point, got {' '.join(head)!r}")
    n = h[0]
    body = recs[1:n + 1]
    if len(body) < n:
        raise MeshFormatError(f"{node}: the header (line {ln}) announces {n} points, the file has {len(body)}")
    numbers = np.empty(n, dtype=np.int64)
    V = np.empty((n, 3))
    for k, (line, toks) in enumerate(body):
        if len(toks) < 4:
            raise MeshFormatError(f"{node}, line {line}: a point needs a number and 3 coordinates, got "
                                  f"{' '.join(toks)!r}")
        numbers[k] = _ints(node, line, toks[:1], "point numbers")[0]
        try:
            V[k] = [float(t) for t in toks[1:4]]
        except ValueError:
            raise MeshFormatError(f"{node}, line {line}: coordinates must be numbers, got "
                                  f"{' '.join(toks[1:4])!r}") from None
        if not np.all(np.isfinite(V[k])):
            raise MeshFormatError(f"{node}, line {line}: point {numbers[k]} has a non-finite coordinate")
    return V, numbers


def _read_ele(ele: Path, node: Path, numbers: np.ndarray) -> tuple[np.ndarray, int]:
    """The tetrahedra (k, 4) of an ``.ele`` file as indices into the points of ``numbers``, and the nodes per
    element (4 or 10)."""
    order = np.argsort(numbers, kind="stable")
    known_numbers = numbers[order]
    dup = known_numbers[1:] == known_numbers[:-1]
    if dup.any():
        raise MeshFormatError(f"{node}: point number {int(known_numbers[1:][dup][0])} is given more than once")
    recs = _records(ele)
    ln, head = recs[0]
    h = _ints(ele, ln, head[:3], "the header (tetrahedra, nodes per tetrahedron, attributes)")
    if len(h) < 2 or h[0] < 1 or h[1] not in (4, 10):
        raise MeshFormatError(f"{ele}, line {ln}: the header must be '<tetrahedra> <4 or 10> [attributes]' with at "
                              f"least one tetrahedron, got {' '.join(head)!r}")
    k_tets, per = h[0], h[1]
    body = recs[1:k_tets + 1]
    if len(body) < k_tets:
        raise MeshFormatError(f"{ele}: the header (line {ln}) announces {k_tets} tetrahedra, the file has {len(body)}")
    raw = np.empty((k_tets, 4), dtype=np.int64)
    for k, (line, toks) in enumerate(body):
        if len(toks) < 1 + per:
            raise MeshFormatError(f"{ele}, line {line}: a tetrahedron needs a number and {per} point numbers, got "
                                  f"{' '.join(toks)!r}")
        raw[k] = _ints(ele, line, toks[1:5], "point numbers")
    pos = np.clip(np.searchsorted(known_numbers, raw), 0, numbers.size - 1)
    known = known_numbers[pos] == raw
    if not known.all():
        k = int(np.flatnonzero(~known.all(axis=1))[0])
        bad = int(raw[k][~known[k]][0])
        raise MeshFormatError(f"{ele}, line {body[k][0]}: tetrahedron {body[k][1][0]} names point {bad}, which "
                              f"{node.name} does not have")
    return order[pos], per


def _records(path: Path) -> list[tuple[int, list[str]]]:
    """Non-empty lines of ``path`` without ``#`` comments, as (line number, tokens); at least one."""
    check_file(path, "a TetGen file")  # a FIFO named x.node would block the open below, a device never end
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise MeshFormatError(f"{path}: cannot read the file ({exc.strerror or exc})") from None
    out = []
    for i, line in enumerate(text.splitlines(), start=1):
        toks = line.split("#", 1)[0].replace(",", " ").split()
        if toks:
            out.append((i, toks))
    if not out:
        raise MeshFormatError(f"{path}: file is empty")
    return out


def _ints(path: Path, line: int, toks: list[str], what: str) -> list[int]:
    """``toks`` as integers that fit int64, or a MeshFormatError naming the file and line."""
    try:
        values = [int(t) for t in toks]
    except ValueError:
        raise MeshFormatError(f"{path}, line {line}: {what} must be integers, got {' '.join(toks)!r}") from None
    for t, v in zip(toks, values, strict=True):
        if not -_INT_LIMIT < v < _INT_LIMIT:
            raise MeshFormatError(f"{path}, line {line}: {what}: {t} is out of range (at most 2**63 - 1)")
    return values
