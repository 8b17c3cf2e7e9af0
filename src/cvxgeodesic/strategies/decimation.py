"""The decimated copy of an adapted solve (``resolution=``): quadric decimation, its checks and its retries.

:func:`_decimated_parts` makes the copy that :mod:`~cvxgeodesic.strategies.adapted` solves on: fast-simplification's
quadric decimation with the boundary kept (:func:`~cvxgeodesic.mesh.decimate.simplify_mesh`), fins removed, a copy that
changes the topology refused and the decimation tried again at other targets and aggressiveness values, a folded
copy (:func:`fold_excess`) tried again at a gentler one, and a mesh in several components decimated one component at
a time. Measured in docs/adapted.md and its development log.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..mesh.decimate import euler_characteristic, simplify_mesh
from ..mesh.simplex import unique_rows
from ..mesh.trimesh import TriMesh

__all__ = ["CLOUD_AGGS", "CREASE_ANGLE", "FOLD_ANGLE", "FOLD_MARGIN", "MAX_FACES_OVER", "MIN_PART_FACES",
           "MIN_RESOLUTION_FACES", "RETRY_AGGS", "RETRY_TARGETS", "RETRY_TARGETS_LATER", "SIMPLIFIER", "fold_excess",
           "fold_reference", "max_turn"]

#: The smallest face count ``resolution`` takes.
MIN_RESOLUTION_FACES = 4

#: The targets (times the asked face count) tried in turn until a copy keeps the mesh's topology.
RETRY_TARGETS = (1.0, 1.02, 0.98, 1.05, 0.95)
#: ... all of them at the first aggressiveness (:data:`RETRY_AGGS`), the first this many at the others (each try is a
#: decimation: bounded set-up time).
RETRY_TARGETS_LATER = 3

#: A point cloud's surface is decimated at these aggressiveness values (at
#: :data:`~cvxgeodesic.strategies.adapted.CLOUD_TARGETS` targets each): on the clouds of 14 shared meshes at 0, 0.1,
#: 0.2 and 0.3 % noise (56 surfaces, 2026-12-06), 5 kept a copy where 7 failed twice and 3 never did, while each
#: failed try costs a decimation (0.03-0.18 s, 0.2-0.3x the point-cloud heat method's time) before the fallback to
#: order 1.
CLOUD_AGGS = (7.0, 5.0)
#: fast-simplification's aggressiveness for the copies, tried in turn (:func:`_decimated`): 7 first (its default, the
#: best on most meshes), then 5 and 3 for a copy that 7 folds or breaks (measured in docs/adapted.md).
RETRY_AGGS = (7.0, 5.0, 3.0)
#: A copy is folded where an edge of it turns by more than ``FOLD_ANGLE`` degrees (angle between its faces' normals)
#: and by more than ``FOLD_MARGIN`` degrees beyond the user's sharpest turn anywhere (:func:`fold_excess`); not on
#: a mesh with creases: 0.1 % of its edges turning by ``CREASE_ANGLE`` degrees or more (:func:`fold_reference`).
FOLD_ANGLE = 100.0
FOLD_MARGIN = 30.0
CREASE_ANGLE = 60.0
#: A copy of a gentler aggressiveness than the most aggressive that stops above this many times the target faces is
#: refused (dragon at 1/10 with agg 3 stopped at 3,826 of 2,000 faces, which costs more than the target's solve; the
#: estimate's copy would be nearly the solve copy). The most aggressive copy is kept however many faces it has (a
#: kept boundary stops the decimation early on a small mesh; no gentler one gets further).
MAX_FACES_OVER = 1.25
#: A mesh in several components is decimated one component at a time, each to its share of the target; a component
#: whose share is below this many faces is kept as it is (a speck of a scan: too small to gain from a copy).
MIN_PART_FACES = 50
#: How the solve mesh is made (recorded in ``info.extra["adapted"]["simplifier"]``).
SIMPLIFIER = "quadric (fast-simplification, boundary kept)"


def _unsuitable(mesh: TriMesh) -> str | None:
    """Why the mesh is not decimated (solved on itself instead), or None; several components are decimated one at a
    time (:func:`_decimated_parts`)."""
    if not mesh.is_edge_manifold:
        return "the mesh is not edge-manifold (quadric decimation can merge its sheets)"
    if mesh.degenerate_faces(0.0).size:
        return f"the mesh has {mesh.degenerate_faces(0.0).size} face(s) of zero area"
    return None


def _decimated(mesh: TriMesh, target: int, first_agg: float | None = None, targets: int | None = None,
               aggs: tuple[float, ...] = RETRY_AGGS) -> tuple[TriMesh | None, str | None, dict[str, Any]]:
    """The quadric copy of ``mesh`` with about ``target`` faces, ``(None, why, record)`` when no try gave one.

    The aggressiveness values ``aggs`` are tried in turn (``first_agg`` first when given; :data:`CLOUD_AGGS` for a
    point cloud's surface), and at each the targets of :data:`RETRY_TARGETS` (:data:`RETRY_TARGETS_LATER` of them
    after the first aggressiveness; at most ``targets`` of them when given: :data:`CLOUD_TARGETS` for a point cloud's
    surface): a copy that changes the topology is refused and the next target tried (the collapses that break a copy
    depend on where the decimation stops); a folded copy (:func:`fold_excess`) moves on to the next aggressiveness
    (its folds do not go away with a few faces more or less: bimba at 1/10). The first copy neither refused nor folded
    is kept; when every copy is folded, the least folded one, with a note.

    Returns
    -------
    coarse : TriMesh or None
        The copy, or None.
    why : str or None
        Why no copy was kept (the last refusal), or None.
    record : dict
        ``agg`` (the kept copy's aggressiveness), ``fold_angle`` (its largest dihedral turn, degrees), ``folded``
        (kept although folded), ``mesh_turn`` (the user's largest turn, :func:`fold_reference`) and ``tries`` (one
        ``(agg, target, outcome)`` per decimation).
    """
    why: str | None = None
    tries: list[tuple[float, int, str]] = []
    folded: tuple[float, TriMesh, dict[str, Any]] | None = None
    mesh_turn = fold_reference(mesh)
    aggs = aggs if first_agg is None else (first_agg, *(a for a in aggs if a != first_agg))
    for i, agg in enumerate(aggs):
        factors = RETRY_TARGETS if i == 0 else RETRY_TARGETS[:RETRY_TARGETS_LATER]
        for factor in factors[:targets]:
            faces = max(MIN_RESOLUTION_FACES, int(round(factor * target)))
            coarse, why = _decimated_once(mesh, faces, agg)
            if coarse is None:
                tries.append((agg, faces, str(why)))
                continue
            excess, angle = fold_excess(coarse, mesh_turn)
            record = {"agg": agg, "fold_angle": angle, "mesh_turn": mesh_turn, "folded": excess > 0}
            if excess <= 0:
                tries.append((agg, faces, "kept"))
                return coarse, None, {**record, "tries": tries}
            tries.append((agg, faces, f"folded (an edge turns {angle:.0f} deg, the mesh at most {mesh_turn:.0f})"))
            if folded is None or excess < folded[0]:
                folded = (excess, coarse, record)
            break  # a fold stays at nearby targets: the next aggressiveness
    if folded is not None:
        return folded[1], None, {**folded[2], "tries": tries}
    return None, why, {"tries": tries}


def _decimated_parts(mesh: TriMesh, target: int, first_agg: float | None = None, targets: int | None = None,
                     aggs: tuple[float, ...] = RETRY_AGGS, *, face_label: np.ndarray,
                     ) -> tuple[TriMesh | None, str | None, dict[str, Any]]:
    """:func:`_decimated` of a mesh in one or several components: each component decimated on its own to its share
    of ``target`` (the decimation never sees two, so it cannot merge them), or kept as it is below
    :data:`MIN_PART_FACES`, and the copies put side by side. ``face_label`` (m,) labels each face's component: the
    mesh's own components, or for a point cloud's surface the piece of the cloud's own triangles its points are in
    (which the cloud's points are read by; one connected piece of the surface to a label).

    Returns
    -------
    coarse, why, record
        As :func:`_decimated`; with several components the record's ``tries`` name the component, ``agg`` is the
        largest decimated component's, and ``part_of_face`` (the copy's faces' labels, ``face_label``'s) and
        ``components`` are added.
    """
    labels, counts = np.unique(face_label, return_counts=True)
    if labels.size == 1:
        return _decimated(mesh, target, first_agg, targets, aggs)
    V, F, part_of_face, tries = [], [], [], []
    record: dict[str, Any] = {"agg": None, "fold_angle": 0.0, "mesh_turn": 0.0, "folded": False,
                              "components": int(labels.size)}
    offset, largest = 0, -1
    for k, (label, count) in enumerate(zip(labels, counts, strict=True)):
        faces = mesh.F[face_label == label]
        used = np.unique(faces)
        part = TriMesh(mesh.V[used], np.searchsorted(used, faces), name=f"{mesh.name}[component {k + 1}]")
        share = int(round(target * count / mesh.n_faces))
        if share < count and share >= MIN_PART_FACES:
            copy, why, made = _decimated(part, share, first_agg, targets, aggs)
            tries += [(a, t, f"component {k + 1} of {labels.size}: {o}") for a, t, o in made["tries"]]
            if copy is None:
                return None, f"component {k + 1} of {labels.size} ({count} faces): {why}", {"tries": tries}
            part = copy
            record["fold_angle"] = max(record["fold_angle"], made["fold_angle"])
            record["mesh_turn"] = max(record["mesh_turn"], made["mesh_turn"])
            record["folded"] |= made["folded"]
            if count > largest:
                record["agg"], largest = made["agg"], count
        V.append(part.V)
        F.append(part.F + offset)
        part_of_face.append(np.full(part.n_faces, label))
        offset += part.n_vertices
    if record["agg"] is None:
        return None, (f"each of its {labels.size} components' share of the {target}-face target is below "
                      f"{MIN_PART_FACES} faces or above its own"), {"tries": tries}
    coarse = TriMesh(np.vstack(V), np.vstack(F), name=mesh.name)
    coarse.simplifier = SIMPLIFIER
    return coarse, None, {**record, "tries": tries, "part_of_face": np.concatenate(part_of_face)}


def fold_excess(coarse: TriMesh, mesh_turn: float) -> tuple[float, float]:
    """How much sharper the copy turns than the user's mesh anywhere: a folded copy.

    A quadric collapse can fold the copy over itself where the user's surface is smooth (bimba at 1/10: an edge of
    the copy turns by 132 deg where the mesh turns by at most 84 deg, and even the exact distance on that copy, read
    at the user's vertices, is 1.69 % off). The copy is folded where its sharpest turn exceeds both
    :data:`FOLD_ANGLE` and the user's sharpest turn plus :data:`FOLD_MARGIN`. The user's sharpest turn is taken over
    the whole mesh, not near the same place: measured on lucy, buddha, dragon and camelhead, a local comparison
    (the sharpest user edge projected near each sharp copy edge) flagged copies at every aggressiveness, including
    the agg-7 copies that measure best there (docs/adapted.md).

    Parameters
    ----------
    coarse : TriMesh
        The copy.
    mesh_turn : float
        The user's mesh's sharpest turn (degrees, :func:`fold_reference`: 180 on a creased mesh).

    Returns
    -------
    excess : float
        ``turn − max(FOLD_ANGLE, mesh_turn + FOLD_MARGIN)`` for the copy's sharpest turn (degrees; ``<= 0``: not
        folded).
    angle : float
        The copy's sharpest turn (degrees).
    """
    angle = max_turn(coarse)
    return angle - max(FOLD_ANGLE, mesh_turn + FOLD_MARGIN), angle


def max_turn(mesh: TriMesh) -> float:
    """The largest angle between the normals of two faces sharing an edge (degrees: 0 flat, 180 folded onto
    itself); edges with other than two faces are left out (0 for a mesh without such edges)."""
    return float(_turns(mesh).max(initial=0.0))


def fold_reference(mesh: TriMesh) -> float:
    """The user's turn that a copy must exceed by :data:`FOLD_MARGIN` to be folded: the mesh's sharpest turn, or
    180 (no copy is folded) on a creased mesh, where more than 0.1 % of the edges turn by :data:`CREASE_ANGLE` or
    more (a CAD part): there a copy's sharp turn is a crease's corner (fandisk at 2,000 faces: the agg-7 copy turning
    by 155 deg, its mesh at most 92 deg, measured 0.445 % mean error, the agg-5 copy 0.604 %)."""
    turns = _turns(mesh)
    if turns.size == 0:
        return 0.0
    return 180.0 if float(np.percentile(turns, 99.9)) >= CREASE_ANGLE else float(turns.max())


def _turns(mesh: TriMesh) -> np.ndarray:
    """The angle (degrees) between the normals of the two faces of every edge that has two."""
    fe = mesh.cell_edges.ravel()
    fi = np.repeat(np.arange(mesh.n_faces), 3)
    order = np.argsort(fe, kind="stable")
    fe, fi = fe[order], fi[order]
    pair = np.flatnonzero(fe[1:] == fe[:-1])
    normals = mesh.face_normals_unnormalized
    normals = normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), np.finfo(float).tiny)
    cos = np.einsum("ij,ij->i", normals[fi[pair]], normals[fi[pair + 1]])
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def _without_fins(mesh: TriMesh) -> TriMesh:
    """``mesh`` without the faces that appear twice (a collapse can fold two faces onto each other, opposite ways:
    a fin of no area that makes their edges non-manifold; measured on bimba at 1/10), nor the vertices they left."""
    _, inverse, counts = unique_rows(np.sort(mesh.F, axis=1), mesh.n_vertices)
    keep = counts[inverse] == 1
    if keep.all():
        return mesh
    used, local = np.unique(mesh.F[keep], return_inverse=True)
    return TriMesh(mesh.V[used], local.reshape(-1, 3), name=mesh.name)


def _decimated_once(mesh: TriMesh, target: int, agg: float = 7.0) -> tuple[TriMesh | None, str | None]:
    try:
        coarse = _without_fins(simplify_mesh(mesh, target, method="quadric", preserve_border=True, agg=agg))
    except Exception as exc:  # noqa: BLE001 - any failure of the extension falls back, with its message
        return None, f"the decimation failed ({type(exc).__name__}: {exc})"
    checks = ((not coarse.is_edge_manifold, "the decimated copy has non-manifold edges"),
              (coarse.n_components != 1, f"the decimated copy has {coarse.n_components} components"),
              (euler_characteristic(coarse) != euler_characteristic(mesh),
               f"the decimated copy changed the Euler characteristic ({euler_characteristic(mesh)} -> "
               f"{euler_characteristic(coarse)})"),
              (coarse.degenerate_faces(0.0).size > 0, "the decimated copy has faces of zero area"),
              (agg < max(RETRY_AGGS) and coarse.n_faces > MAX_FACES_OVER * target,
               f"the decimation stopped at {coarse.n_faces} faces"))
    for bad, why in checks:
        if bad:
            return None, why
    coarse.simplifier = SIMPLIFIER
    return coarse, None
