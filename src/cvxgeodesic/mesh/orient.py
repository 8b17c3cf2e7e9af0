"""Consistent face orientation, for the computations that depend on it.

Two faces that share an edge are *consistently oriented* when they run through it in opposite directions. A
geodesic distance does not depend on the orientation, but two computations do: potpourri3d's fast marching
(``fmm``: reversing every other face of an icosphere moved its field by 10 % of the largest distance) and
libigl's curved Hessian energy (``qcqp-hessian``: 7e-5 of it). Both are therefore given the mesh with its faces
oriented consistently by :func:`orient_faces`, and the repair is recorded (:meth:`Orientation.note`).

Faces are oriented across the edges with exactly two faces, in each piece connected through such edges, keeping
the orientation of the majority of its faces (so a mesh with a few reversed faces has those turned). A piece
that cannot be oriented (a Möbius strip) keeps its faces as given and is reported instead.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

__all__ = ["Orientation", "orient_faces"]


@dataclass(frozen=True)
class Orientation:
    """The faces of a mesh oriented consistently (:func:`orient_faces`).

    Attributes
    ----------
    F : (m, 3) int64 ndarray
        The faces, those in :attr:`flipped` with their corners reversed (``[a, b, c] → [c, b, a]``).
    flipped : (m,) bool ndarray
        The faces that were reversed.
    non_orientable : (m,) bool ndarray
        The faces of pieces that cannot be oriented consistently (kept as given).
    """

    F: np.ndarray
    flipped: np.ndarray
    non_orientable: np.ndarray

    @property
    def changed(self) -> bool:
        """True when a face was reversed or a piece cannot be oriented (something to report)."""
        return bool(self.flipped.any() or self.non_orientable.any())

    def note(self, name: str, what: str) -> str | None:
        """One line for ``info.notes`` (None when the faces were consistent already).

        Parameters
        ----------
        name : str
            The mesh's name.
        what : str
            What depends on the orientation (``"fast marching"``, ``"the curved Hessian energy"``).
        """
        parts = []
        if self.flipped.any():
            parts.append(f"{int(self.flipped.sum())} of {self.F.shape[0]} faces reversed to orient the surface "
                         f"consistently for {what} (first: face {int(np.flatnonzero(self.flipped)[0])})")
        if self.non_orientable.any():
            parts.append(f"{int(self.non_orientable.sum())} faces lie on a non-orientable piece (a Möbius strip or "
                         f"the like; first: face {int(np.flatnonzero(self.non_orientable)[0])}): {what} sees them "
                         "as given")
        return f"{name}: " + "; ".join(parts) if parts else None

    def bary(self, faces: np.ndarray, bary: np.ndarray) -> np.ndarray:
        """Barycentric coordinates ``(k, 3)`` in ``faces`` of the original mesh, rewritten for the oriented faces."""
        out = np.array(bary, dtype=np.float64, copy=True).reshape(-1, 3)
        rev = self.flipped[np.asarray(faces, dtype=np.int64)]
        out[rev] = out[rev, ::-1]
        return out


def orient_faces(F: np.ndarray, n: int) -> Orientation:
    """Orient the faces consistently across every edge shared by exactly two faces.

    Each face has two states (as given, reversed); an edge of two faces joins the states that agree along it. A piece
    of faces connected through such edges is orientable when a face's two states fall into different components of
    that state graph; the component holding most faces' "as given" state is kept.

    Parameters
    ----------
    F : (m, 3) int array_like
        Triangles as vertex indices.
    n : int
        Vertex count.

    Returns
    -------
    Orientation
    """
    F = np.asarray(F, dtype=np.int64)
    m = F.shape[0]
    tail = F.ravel()  # half-edge (t, k) runs from F[t, k] to F[t, k + 1]
    head = F[:, [1, 2, 0]].ravel()
    face = np.repeat(np.arange(m), 3)
    key = np.minimum(tail, head) * np.int64(n) + np.maximum(tail, head)
    order = np.argsort(key)
    k_sorted = key[order]
    start = np.flatnonzero(np.r_[True, k_sorted[1:] != k_sorted[:-1]])
    count = np.diff(np.r_[start, k_sorted.size])
    first = order[start[count == 2]]
    second = order[start[count == 2] + 1]
    # the same direction in both faces: one of them must be reversed
    differ = (tail[first] == tail[second]).astype(np.int64)
    if not differ.any():  # consistent already (hence orientable): the common case, one sort
        none = np.zeros(m, dtype=bool)
        return Orientation(F, none, none.copy())
    t1, t2 = face[first], face[second]
    # state node of face t: t (as given) and m + t (reversed)
    rows = np.r_[t1, t1 + m]
    cols = np.r_[t2 + m * differ, t2 + m * (1 - differ)]
    graph = sp.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(2 * m, 2 * m))
    _, label = connected_components(graph, directed=False)
    given, reversed_ = label[:m], label[m:]
    non_orientable = given == reversed_
    # per piece, keep the state component holding the smaller label, then the majority of "as given"
    keep = np.minimum(given, reversed_)
    flipped = (reversed_ == keep) & ~non_orientable
    piece_flips = np.bincount(keep, weights=flipped, minlength=2 * m)
    piece_size = np.bincount(keep, minlength=2 * m)
    flipped ^= (2 * piece_flips[keep] > piece_size[keep]) & ~non_orientable
    out = F.copy()
    out[flipped] = out[flipped, ::-1]
    return Orientation(out, flipped, non_orientable)
