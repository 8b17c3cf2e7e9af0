"""What each method supports: one table, read by the checks at the API edge, the docs and the CLI's help.

A *cell* is a method on a domain (:data:`DOMAINS`: ``"surface"``, triangle meshes; ``"volume"``, tetrahedral meshes;
``"cloud"``, a point cloud's triangle soup; a mesh names its own: ``mesh.domain``) at an element order (1, 2), with a
medium (``"none"``, ``"cost"``, ``"metric"``), a source kind (:data:`SOURCE_KINDS`), with or without ``multires``,
with or without a ``resolution`` other than ``"mesh"`` (an adapted solve) and as full rows or local rows of a
distance matrix (``max_distance``). Every cell is supported unless a rule of :data:`RULES` refuses it; the first such
rule gives the reason. :func:`check` turns a refusal into the library's error (``ParameterError``, or ``SourceError``
for a kind of source) naming what is supported instead, and returns the validated cell (:class:`Capability`): the
API edge calls it once per solver and passes the cell down, whose :meth:`Capability.admit` checks the kinds of
source of each solve against the same rules. :func:`check_path` answers for :func:`~cvxgeodesic.geodesic_path`;
:func:`markdown_table` writes the table of ``docs/capabilities.md`` and :func:`help_text` the short version for the
command line. What else differs by domain (the default method and resolution, the comparison's reference, the
batch's output format, the words of the messages) is its :class:`Domain` record.

A leaf module (no NumPy): the method names are spelled here and a test checks them against
:data:`~cvxgeodesic.problems.formulations.FORMULATIONS` and :data:`~cvxgeodesic.baselines.BASELINES`.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from .errors import ParameterError, SourceError

__all__ = ["BASELINE_METHODS", "Capability", "DOMAINS", "Domain", "FORMULATION_METHODS", "MEDIA", "METHODS",
           "ORDERS", "RULES", "Rule", "SOURCE_KINDS", "check", "check_path", "help_text", "markdown_table",
           "methods_for", "refusal", "source_kinds", "source_phrase", "supported"]

#: The eight convex formulations.
FORMULATION_METHODS = ("lclp", "lcqp-dirichlet", "lcqp-laplacian", "lcqp-hessian", "qclp", "qcqp-dirichlet",
                       "qcqp-laplacian", "qcqp-hessian")
#: The baselines (:data:`~cvxgeodesic.baselines.BASELINES`).
BASELINE_METHODS = ("dijkstra", "fmm", "heat", "exact")
METHODS = (*FORMULATION_METHODS, *BASELINE_METHODS)
#: The element orders (:func:`~cvxgeodesic.validation.check_order`).
ORDERS = (1, 2)
MEDIA = ("none", "cost", "metric")
#: Kinds of source: vertex indices, a point inside a cell (SurfacePoint, VolumePoint), a SurfaceCurve, the whole
#: boundary (``"boundary"``), part of a volume's boundary (BoundaryFaces).
SOURCE_KINDS = ("vertex", "point", "curve", "boundary", "boundary faces")


@dataclass(frozen=True)
class Domain:
    """What the library does differently on one domain, beside its rules.

    Attributes
    ----------
    name : str
        The domain (``mesh.domain``).
    meshes : str
        How messages name its meshes (``"triangle meshes"``).
    where, on : str
        Where a solve runs, in a source message (``"inside a volume"``) and in a method message (``"on a volume"``).
    dim : int
        The simplex dimension of its cells (a mesh file format holds cells of a dimension: ``Format.dims``).
    default_method : str
        The method of ``method=None`` (``GeodesicSolver``, the CLI, batches).
    default_resolution : "mesh", "auto", int or float
        The ``resolution`` of ``resolution=None`` and ``order=None`` (docs/adapted.md); a given order, local rows,
        multires, and a method, medium or smoothing without an adapted solve take ``"mesh"`` whatever this says.
    reference : (str, int)
        The comparison's reference field (:mod:`cvxgeodesic.compare`): ``(method, order)``.
    output_format : str
        A batch's distance file when no format is given (:mod:`cvxgeodesic.batch`).
    drawn_as : str
        What the viewer draws (:func:`cvxgeodesic.viewer.show`): ``"cells"``, the mesh as its cell kind is drawn
        (``reference.picture``); ``"points"``, its vertices coloured by the field (a cloud's soup of overlapping fans
        is no surface to shade).
    vertex_words, cell_words : str
        How the command line counts its vertices and cells (``"points"``, ``"fan triangles"`` on a cloud); an empty
        ``cell_words`` takes the cell kind's (``reference.words.many``).
    """

    name: str
    meshes: str
    where: str
    on: str
    dim: int
    default_method: str
    default_resolution: Any
    reference: tuple[str, int]
    output_format: str
    drawn_as: str = "cells"
    vertex_words: str = "vertices"
    cell_words: str = ""


#: Every domain by name (``mesh.domain``). The curved Hessian energy exists on surfaces only: ``qclp`` in a volume;
#: on a point cloud ``qclp`` at order 2 on a decimated copy of the surface through the points (``"auto"``), which
#: falls back to order 1 on the cloud's own triangles where the copy is refused (docs/pointclouds.md). Where no exact
#: method applies (a volume, a cloud's soup) the comparison's reference is the most accurate field the library
#: computes there, ``qclp`` at order 2.
DOMAINS: dict[str, Domain] = {
    "surface": Domain("surface", "triangle meshes", "on a surface", "on a surface", 2, "qcqp-hessian", "mesh",
                      ("exact", 1), "ply"),
    "volume": Domain("volume", "tetrahedral meshes", "inside a volume", "on a volume", 3, "qclp", "mesh",
                     ("qclp", 2), "vtu"),
    "cloud": Domain("cloud", "point clouds", "on a point cloud", "on a point cloud", 2, "qclp", "auto",
                    ("qclp", 2), "ply", drawn_as="points", vertex_words="points", cell_words="fan triangles"),
}

_HESSIAN = ("lcqp-hessian", "qcqp-hessian")
_LC = ("lclp", "lcqp-dirichlet", "lcqp-laplacian", "lcqp-hessian")
_QC_SMOOTHED = ("qcqp-dirichlet", "qcqp-laplacian", "qcqp-hessian")
_EUCLIDEAN = ("fmm", "heat", "exact")
_WITH_MEDIUM = ("cost", "metric")
#: The domains of triangles: a cloud's soup is a triangle mesh, so the surfaces' rules hold there too.
_TRIANGLES = ("surface", "cloud")
_NOT_VERTICES = ("point", "curve", "boundary", "boundary faces")
_CLOUD_MANIFOLD = "it needs a manifold surface; a cloud's triangles are overlapping fans, not one"
_CLOUD_HESSIAN = ("the curved Hessian energy needs a consistently oriented surface; a cloud's overlapping fans have "
                  "none (use qcqp-dirichlet or qcqp-laplacian for a smoothed field)")


@dataclass(frozen=True)
class Rule:
    """One refusal: the cells it matches are not supported, for ``reason``.

    Attributes
    ----------
    axis : {"method", "local", "resolution", "order", "medium", "multires", "source", "path"}
        What the rule is about (it matches only where that axis is asked for: local rows, a medium, a source kind,
        multires, a path; "order" rules name order 2). Decides the message and the error class.
    reason : str
        Why, in a few words (the table's footnote and the message's parenthesis).
    methods, domains, orders, media, sources : tuple, optional
        The cells it matches; None matches any value.
    smoothing : bool
        Matches only a smoothed solve (``m > 0`` or ``lam > 0``); the table shows such cells as "m = 0 only".
    also : tuple of str
        Other axes the cell must ask for too (``("multires",)``: local rows with multires).
    """

    axis: str
    reason: str
    methods: tuple[str, ...] | None = None
    domains: tuple[str, ...] | None = None
    orders: tuple[int, ...] | None = None
    media: tuple[str, ...] | None = None
    sources: tuple[str, ...] | None = None
    smoothing: bool = False
    also: tuple[str, ...] = ()

    def matches(self, method: str, domain: str, order: int, medium: str, source: str | None, multires: bool,
                smoothing: bool, resolution: bool = False, local: bool = False, path: bool = False) -> bool:
        """Whether the cell is one this rule refuses."""
        asked = {"method": True, "order": order != 1, "medium": medium != "none", "multires": multires,
                 "source": source is not None, "resolution": resolution, "local": local, "path": path}
        return (all(asked[a] for a in (self.axis, *self.also)) and (self.methods is None or method in self.methods)
                and (self.domains is None or domain in self.domains) and (self.orders is None or order in self.orders)
                and (self.media is None or medium in self.media)
                and (self.sources is None or source in self.sources) and (smoothing or not self.smoothing))


#: Every refusal, read from the code of the solvers.
RULES: tuple[Rule, ...] = (
    # method × domain
    Rule("method", "the curved Hessian energy is defined on surfaces", _HESSIAN, domains=("volume",)),
    Rule("method", "it is a surface algorithm", ("fmm", "exact"), domains=("volume",)),
    Rule("method", _CLOUD_MANIFOLD, ("exact", "fmm"), domains=("cloud",)),
    Rule("method", _CLOUD_HESSIAN, _HESSIAN, domains=("cloud",)),
    # local rows of a distance matrix (max_distance=, rows.LocalRows: each row solved on a patch around its source)
    Rule("local", "local rows are solved on patches of a triangle mesh; a tetrahedral mesh takes full rows",
         domains=("volume",)),
    Rule("local", "max_distance does not take multires= (a patch has no coarse mesh of its own yet)",
         also=("multires",)),
    Rule("local", "max_distance does not take cost= or metric= (a patch has no travel cost or metric of its own yet)",
         media=_WITH_MEDIUM),
    Rule("local", "max_distance does not take resolution= (a patch is solved on itself, not on a decimated copy)",
         also=("resolution",)),
    Rule("local", "local rows take source vertices (ints), one row per vertex", sources=_NOT_VERTICES),
    # order 2 (the P2 squared distance)
    Rule("order", "the baselines have no order-2 variant", BASELINE_METHODS, orders=(2,)),
    Rule("order", "the LC formulations' edge bounds have no order-2 program", _LC, orders=(2,)),
    Rule("order", "the order-2 smoothness energies are implemented on surfaces only", _QC_SMOOTHED,
         domains=("volume",), orders=(2,)),
    # travel cost and metric
    Rule("medium", "travel costs and metrics are implemented on surfaces only", domains=("volume",),
         media=_WITH_MEDIUM),
    Rule("medium", "its library computes Euclidean distances", _EUCLIDEAN, media=_WITH_MEDIUM),
    Rule("medium", "the order-2 smoothing energies vanish on the Euclidean squared distance only; use "
         "method='qclp' (or m=0) at order 2, or order=1", _QC_SMOOTHED, orders=(2,), media=_WITH_MEDIUM,
         smoothing=True),
    # coarse-to-fine
    Rule("multires", "multires applies to triangle meshes, not to tetrahedral ones", domains=("volume",)),
    Rule("multires", "multires coarsens a mesh; solve a cloud on its own triangles", domains=("cloud",)),
    Rule("multires", "multires applies to the convex formulations, not to the baselines", BASELINE_METHODS),
    Rule("multires", "multires applies at order 1 (order=2 applies without multires)", orders=(2,)),
    Rule("multires", "cost and metric are not implemented with multires; solve on the mesh itself",
         media=_WITH_MEDIUM),
    Rule("multires", "multires takes vertex sources only; solve point, curve and boundary sources without "
         "multires", sources=_NOT_VERTICES),
    # an adapted solve (resolution= other than "mesh": order 2 on a decimated copy, strategies/adapted.py)
    Rule("resolution", "resolution= decimates triangle meshes; tetrahedral meshes are solved on themselves",
         domains=("volume",)),
    Rule("resolution", "resolution= solves at order 2, which the baselines do not have; give resolution='mesh'",
         BASELINE_METHODS),
    Rule("resolution", "resolution= solves at order 2, which the LC formulations do not have; use qclp or a qcqp "
         "method, or resolution='mesh'", _LC),
    Rule("resolution", "resolution= solves at order 2, which takes no curves; solve curves with resolution='mesh'",
         sources=("curve",)),
    # kinds of source
    Rule("source", "a SurfaceCurve lies on a surface; inside a volume give VolumePoints or BoundaryFaces",
         domains=("volume",), sources=("curve",)),
    Rule("source", "BoundaryFaces are faces of a volume's boundary; on a surface give 'boundary' or a "
         "SurfaceCurve", domains=_TRIANGLES, sources=("boundary faces",)),
    Rule("source", "a cloud's boundary is not detected (the fans' free edges are everywhere the fans disagree); "
         "give the boundary's points by index", domains=("cloud",), sources=("boundary",)),
    Rule("source", "curves are resampled on a manifold surface; give the curve's points by index or as "
         "SurfacePoints", domains=("cloud",), sources=("curve",)),
    Rule("source", "potpourri3d's heat method takes vertex sources only", ("heat",), domains=_TRIANGLES,
         sources=("point", "curve")),
    Rule("source", "solve curves at order 1", domains=_TRIANGLES, orders=(2,), sources=("curve",)),
    # paths (geodesic_path) in a medium
    Rule("path", "inside a tetrahedral mesh the path follows the Euclidean distance", domains=("volume",),
         media=_WITH_MEDIUM),
)
#: The order in which the axes refuse: a path's rules are its own (no method, no solve).
_AXES = ("path", "method", "local", "resolution", "order", "medium", "multires", "source")


def refusal(method: str, *, domain: str, order: int = 1, medium: str = "none", source: str | None = None,
            multires: bool = False, smoothing: bool = True, resolution: bool = False, local: bool = False,
            path: bool = False) -> Rule | None:
    """The first rule that refuses the cell (in the order of the axes: method, local rows, resolution, order, medium,
    multires, source), or None.

    Parameters
    ----------
    method : str
        A canonical name of :data:`METHODS`.
    domain : {"surface", "volume", "cloud"}
        A name of :data:`DOMAINS` (``mesh.domain``).
    order : {1, 2}
    medium : {"none", "cost", "metric"}
    source : str, optional
        One of :data:`SOURCE_KINDS`; None: no source asked about.
    multires : bool
    smoothing : bool
        The solve has a smoothness term (``m > 0``); False lets the smoothed methods behave as their LP.
    resolution : bool
        An adapted solve (``resolution`` other than ``"mesh"``; it runs at order 2).
    local : bool
        Local rows of a distance matrix (``max_distance``).
    path : bool
        A path (:func:`~cvxgeodesic.geodesic_path`) rather than a solve.
    """
    hits = [r for r in RULES
            if r.matches(method, domain, order, medium, source, multires, smoothing, resolution, local, path)]
    return min(hits, key=lambda r: _AXES.index(r.axis)) if hits else None


def supported(method: str, **cell: Any) -> bool:
    """True when no rule refuses the cell (the arguments of :func:`refusal`)."""
    return refusal(method, **cell) is None


def methods_for(domain: str, order: int = 1, medium: str = "none", source: str | None = None, *,
                multires: bool = False, resolution: bool = False, local: bool = False) -> tuple[str, ...]:
    """The methods that support a cell on ``domain``, in the order of :data:`METHODS` (a smoothed solve)."""
    return tuple(m for m in METHODS if supported(m, domain=domain, order=order, medium=medium, source=source,
                                                 multires=multires, resolution=resolution, local=local))


def source_kinds(sources: Any) -> set[str]:
    """The kinds of source (:data:`SOURCE_KINDS`) of a resolved source set:
    :class:`~cvxgeodesic.sources.SourceSet` of either dimension (read by its attributes: this module does not import
    it)."""
    kinds = {"vertex"} if sources.vertices.size else set()
    if sources.boundary:
        return {"boundary"}
    # a curve's samples are point sources too: a set with segments (surfaces) has a curve
    if sources.segment_faces.size:
        kinds.add("curve")
    elif sources.point_faces.size:
        kinds.add("point")
    if sources.facets.size:
        kinds.add("boundary faces")
    return kinds


def source_phrase(kinds: Iterable[str]) -> str:
    """``"point or curve"``, ``"point, curve or boundary"``: kinds of source for a message, in table order."""
    ks = [k for k in SOURCE_KINDS if k in set(kinds)]
    return ks[0] if len(ks) == 1 else f"{', '.join(ks[:-1])} or {ks[-1]}"


@dataclass(frozen=True)
class Capability:
    """A cell :func:`check` accepted: what a solver was built for, passed down to its strategy
    (:class:`~cvxgeodesic.strategies.SolveConfig`), whose sources :meth:`admit` checks at each solve.

    Attributes
    ----------
    method : str
    domain, order, medium, multires, smoothing, resolution, local
        See :func:`refusal`.
    """

    method: str
    domain: str
    order: int = 1
    medium: str = "none"
    multires: bool = False
    smoothing: bool = True
    resolution: bool = False
    local: bool = False

    def cell(self) -> dict[str, Any]:
        """The keywords of :func:`refusal` (the method apart)."""
        return {"domain": self.domain, "order": self.order, "medium": self.medium, "multires": self.multires,
                "smoothing": self.smoothing, "resolution": self.resolution, "local": self.local}

    def admit(self, sources: Iterable[str]) -> None:
        """Raise SourceError when a kind of source (:data:`SOURCE_KINDS`) is one this cell cannot take; the message
        names the methods that can."""
        cell = self.cell()
        refused = [(k, r) for k in SOURCE_KINDS if k in set(sources) and (r := refusal(self.method, source=k, **cell))]
        if refused:
            raise SourceError(_source_message(self.method, *refused[0], cell))


def check(method: str, *, domain: str, order: int = 1, medium: str = "none", sources: Iterable[str] = (),
          multires: bool = False, smoothing: bool = True, resolution: bool = False,
          local: bool = False) -> Capability:
    """The cell, when the table supports it; else the library's error, whose message says what is supported instead.

    Parameters
    ----------
    method : str
        A canonical name of :data:`METHODS` (aliases resolved, unknown names refused by the caller).
    domain, order, medium, multires, smoothing, resolution, local
        See :func:`refusal`.
    sources : iterable of str
        Kinds of source known already (:data:`SOURCE_KINDS`); those of each solve go to :meth:`Capability.admit`.

    Returns
    -------
    Capability

    Raises
    ------
    ParameterError
        The method on this domain, at this order, with this medium, with multires, resolution or as local rows.
    SourceError
        A kind of source the method cannot take there (the message names the methods that can).
    """
    cap = Capability(method, domain, order, medium, multires, smoothing, resolution, local)
    rule = refusal(method, **cap.cell())
    if rule is not None:
        raise ParameterError(_message(rule, method, **cap.cell()))
    cap.admit(sources)
    return cap


def check_path(*, domain: str, medium: str = "none") -> None:
    """Raise ParameterError where a path (:func:`~cvxgeodesic.geodesic_path`) cannot follow ``medium`` on ``domain``."""
    rule = next((r for r in RULES if r.axis == "path" and r.matches("", domain, 1, medium, None, False, False,
                                                                     path=True)), None)
    if rule is not None:
        raise ParameterError(f"cost and metric apply to paths on {_paths_with_medium()}; {rule.reason}")


def _paths_with_medium() -> str:
    """The meshes whose paths take a medium, for a message."""
    names = [d.meshes for d in DOMAINS.values() if not any(
        r.axis == "path" and r.matches("", d.name, 1, "cost", None, False, False, path=True) for r in RULES)]
    return " and ".join(dict.fromkeys(names))


def _source_message(method: str, kind: str, rule: Rule, cell: dict[str, Any]) -> str:
    """The message of a refused kind of source, with every kind of the domain refused for the same reason
    ("point or curve") and the methods that take it."""
    domain = DOMAINS[cell["domain"]]
    same = [k for k in SOURCE_KINDS if k == kind or (refusal(method, source=k, **cell) == rule
                                                     and methods_for(domain.name, source=k))]
    what = source_phrase(same)
    if rule.axis in ("multires", "resolution"):
        return f"{rule.axis}{'=' if rule.axis == 'resolution' else ''} cannot take {what} sources ({rule.reason})"
    if rule.axis == "local":
        return f"max_distance cannot take {what} sources ({rule.reason})"
    can = [m for m in methods_for(domain.name, cell["order"], cell["medium"], kind, multires=cell["multires"],
                                  resolution=cell["resolution"], local=cell["local"]) if m != method]
    return (f"method {method!r} cannot take {what} sources {domain.where}"
            f"{' at order 2' if cell['order'] == 2 else ''} ({rule.reason}); "
            + (f"methods that can: {', '.join(can)}" if can else "no method can there"))


def _message(rule: Rule, method: str, *, domain: str, order: int, medium: str, multires: bool,
             smoothing: bool, resolution: bool = False, local: bool = False) -> str:
    d = DOMAINS[domain]
    if rule.axis == "resolution":
        return f"resolution= is not available for method {method!r} on {d.meshes}: {rule.reason}"
    if rule.axis == "local":
        return f"max_distance is not available for method {method!r} on {d.meshes}: {rule.reason}"
    if rule.axis == "method":
        return (f"method {method!r} does not apply to {d.meshes} ({rule.reason}); {d.on} use one of "
                f"{', '.join(methods_for(domain))}")
    if rule.axis == "order":
        return (f"order={order} is implemented for {', '.join(methods_for(domain, order))} on {d.meshes}, not for "
                f"{method!r} ({rule.reason}; docs/order2.md)")
    if rule.axis == "medium":
        can = methods_for(domain, order, medium)
        at = f" at order {order}" + (" with m > 0" if rule.smoothing else "") if order != 1 else ""
        return (f"method {method!r} cannot take a travel cost or metric on {d.meshes}{at} ({rule.reason}); "
                + (f"methods that can: {', '.join(can)}" if can else "no method can there"))
    return f"multires is not available for method {method!r} on {d.meshes}: {rule.reason}"


# ---------------------------------------------------------------------------------------------------------------
# the table as text
# ---------------------------------------------------------------------------------------------------------------
_COLUMNS = ("order 1", "order 2", "cost, metric", "multires", "resolution", "max_distance", *SOURCE_KINDS)
#: What a column other than an order's asks of :func:`refusal` (a source column: its kind).
_COLUMN_CELLS: dict[str, dict[str, Any]] = {"cost, metric": {"medium": "cost"}, "multires": {"multires": True},
                                            "resolution": {"resolution": True}, "max_distance": {"local": True}}


def _cell(method: str, domain: str, column: str, notes: dict[str, int]) -> str:
    """One cell of :func:`markdown_table`: "yes", "no [k]", or the orders / condition where it holds."""
    def note(rule: Rule) -> str:
        return f"[{notes.setdefault(rule.reason, len(notes) + 1)}]"

    rule = refusal(method, domain=domain)
    if rule is not None:  # the method does not apply to the domain: said once, in its first column
        return f"no {note(rule)}" if column == "order 1" else "—"
    orders = [o for o in ORDERS if supported(method, domain=domain, order=o)]
    if column in ("order 1", "order 2"):
        rule = refusal(method, domain=domain, order=int(column[-1]))
        return "yes" if rule is None else f"no {note(rule)}"
    kw = _COLUMN_CELLS.get(column, {"source": column})
    verdicts = {o: (refusal(method, domain=domain, order=o, **kw),
                    refusal(method, domain=domain, order=o, smoothing=False, **kw)) for o in orders}
    if all(r is None for r, _ in verdicts.values()):
        return "yes"
    ok = [o for o, (r, _) in verdicts.items() if r is None]
    flat = [o for o, (r, r0) in verdicts.items() if r is not None and r0 is None]
    first = next(r for r, _ in verdicts.values() if r is not None)
    parts = [f"order {o}" for o in ok] + [f"order {o} with m = 0" for o in flat]
    return (f"{', '.join(parts)} {note(first)}" if parts else f"no {note(first)}")


def _path_line(domain: str, notes: dict[str, int]) -> str:
    """The domain's line on paths (:func:`~cvxgeodesic.geodesic_path`) in a medium."""
    rule = next((r for r in RULES if r.axis == "path" and r.matches("", domain, 1, "cost", None, False, False,
                                                                     path=True)), None)
    verdict = "yes" if rule is None else f"no [{notes.setdefault(rule.reason, len(notes) + 1)}]"
    return f"Paths (`geodesic_path`) in a travel cost or metric: {verdict}."


def markdown_table() -> str:
    """The capability table as Markdown: one table per domain, then the numbered reasons.

    ``docs/capabilities.md`` holds this text between its markers (a test checks that it is current).
    """
    notes: dict[str, int] = {}
    out = []
    for domain in DOMAINS.values():
        out += [f"## {domain.meshes.capitalize()}", "",
                "| method | " + " | ".join(_COLUMNS) + " |", "|---" * (len(_COLUMNS) + 1) + "|"]
        out += [f"| `{m}` | " + " | ".join(_cell(m, domain.name, c, notes) for c in _COLUMNS) + " |" for m in METHODS]
        out += ["", _path_line(domain.name, notes), ""]
    out += ['—: the method does not apply to these meshes (its column "order 1" says why).', ""]
    for rule in RULES:  # the rules without a cell of their own (a method's domain, multires' sources) close it
        notes.setdefault(rule.reason, len(notes) + 1)
    out += [f"{k}. {reason}" for reason, k in sorted(notes.items(), key=lambda kv: kv[1])]
    return "\n".join(out) + "\n"


def help_text() -> str:
    """A few lines for the command line's help: the methods, orders and media of each domain."""
    lines = []
    for d in DOMAINS.values():
        lines.append(f"{d.meshes}: methods {', '.join(methods_for(d.name))}; order 2: "
                     f"{', '.join(methods_for(d.name, 2))}; cost/metric: "
                     f"{', '.join(methods_for(d.name, 1, 'cost')) or 'none'}")
    return "\n".join(lines) + "\n(docs/capabilities.md has the whole table, sources included)"
