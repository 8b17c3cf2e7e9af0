"""What each method supports: one table, read by the checks at the API edge, the docs and the CLI's help.

A *cell* is a method on a simplex dimension (2: triangle meshes, 3: tetrahedral meshes) at an element order
(1, 2), with a medium (``"none"``, ``"cost"``, ``"metric"``), a source kind (:data:`SOURCE_KINDS`), with or
without ``multires`` and with or without a ``resolution`` other than ``"mesh"`` (an adapted solve). Every cell is
supported unless a rule of :data:`RULES` refuses it; the first such rule gives the reason. :func:`check` turns a
refusal into the library's error (``ParameterError``, or ``SourceError`` for a kind of source) naming what is
supported instead; :func:`markdown_table` writes the table of ``docs/capabilities.md``
and :func:`help_text` the short version for the command line.

A leaf module (no NumPy): the method names are spelled here and a test checks them against
:data:`~cvxgeodesic.problems.formulations.FORMULATIONS` and :data:`~cvxgeodesic.baselines.BASELINES`.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from .errors import ParameterError, SourceError

__all__ = ["BASELINE_METHODS", "CLOUD_DEFAULT_METHOD", "CLOUD_REFUSALS", "check_cloud", "cloud_methods",
           "DIMS", "FORMULATION_METHODS", "MEDIA", "METHODS", "ORDERS", "RULES", "Rule",
           "SOURCE_KINDS", "check", "help_text", "markdown_table", "methods_for", "refusal", "source_kinds",
           "source_phrase", "supported"]

#: The eight convex formulations.
FORMULATION_METHODS = ("lclp", "lcqp-dirichlet", "lcqp-laplacian", "lcqp-hessian", "qclp", "qcqp-dirichlet",
                       "qcqp-laplacian", "qcqp-hessian")
#: The baselines (:data:`~cvxgeodesic.baselines.BASELINES`).
BASELINE_METHODS = ("dijkstra", "fmm", "heat", "exact")
METHODS = (*FORMULATION_METHODS, *BASELINE_METHODS)
DIMS = (2, 3)
ORDERS = (1, 2)
MEDIA = ("none", "cost", "metric")
#: Kinds of source: vertex indices, a point inside a cell (SurfacePoint, VolumePoint), a SurfaceCurve, the whole
#: boundary (``"boundary"``), part of a volume's boundary (BoundaryFaces).
SOURCE_KINDS = ("vertex", "point", "curve", "boundary", "boundary faces")

#: How the messages name a dimension's meshes.
DIM_NAMES = {2: "triangle meshes", 3: "tetrahedral meshes"}
_ON = {2: "on a surface", 3: "inside a volume"}

_HESSIAN = ("lcqp-hessian", "qcqp-hessian")
_LC = ("lclp", "lcqp-dirichlet", "lcqp-laplacian", "lcqp-hessian")
_QC_SMOOTHED = ("qcqp-dirichlet", "qcqp-laplacian", "qcqp-hessian")
_EUCLIDEAN = ("fmm", "heat", "exact")
_WITH_MEDIUM = ("cost", "metric")


@dataclass(frozen=True)
class Rule:
    """One refusal: the cells it matches are not supported, for ``reason``.

    Attributes
    ----------
    axis : {"method", "resolution", "order", "medium", "multires", "source"}
        What the rule is about (it matches only where that axis is asked for: a medium, a source kind, multires;
        "order" rules name order 2). Decides the message and the error class.
    reason : str
        Why, in a few words (the table's footnote and the message's parenthesis).
    methods, dims, orders, media, sources : tuple, optional
        The cells it matches; None matches any value.
    smoothing : bool
        Matches only a smoothed solve (``m > 0`` or ``lam > 0``); the table shows such cells as "m = 0 only".
    """

    axis: str
    reason: str
    methods: tuple[str, ...] | None = None
    dims: tuple[int, ...] | None = None
    orders: tuple[int, ...] | None = None
    media: tuple[str, ...] | None = None
    sources: tuple[str, ...] | None = None
    smoothing: bool = False

    def matches(self, method: str, dim: int, order: int, medium: str, source: str | None, multires: bool,
                smoothing: bool, resolution: bool = False) -> bool:
        """Whether the cell is one this rule refuses."""
        active = {"method": True, "order": order != 1, "medium": medium != "none", "multires": multires,
                  "source": source is not None, "resolution": resolution}[self.axis]
        return (active and (self.methods is None or method in self.methods)
                and (self.dims is None or dim in self.dims) and (self.orders is None or order in self.orders)
                and (self.media is None or medium in self.media)
                and (self.sources is None or source in self.sources) and (smoothing or not self.smoothing))


#: Every refusal, read from the code of the solvers (which keep their own checks where a direct user reaches them).
RULES: tuple[Rule, ...] = (
    # method × dimension
    Rule("method", "the curved Hessian energy is defined on surfaces", _HESSIAN, dims=(3,)),
    Rule("method", "it is a surface algorithm", ("fmm", "exact"), dims=(3,)),
    # order 2 (the P2 squared distance)
    Rule("order", "the baselines have no order-2 variant", BASELINE_METHODS, orders=(2,)),
    Rule("order", "the LC formulations' edge bounds have no order-2 program", _LC, orders=(2,)),
    Rule("order", "the order-2 smoothness energies are implemented on surfaces only", _QC_SMOOTHED, dims=(3,),
         orders=(2,)),
    # travel cost and metric
    Rule("medium", "travel costs and metrics are implemented on surfaces only", dims=(3,), media=_WITH_MEDIUM),
    Rule("medium", "its library computes Euclidean distances", _EUCLIDEAN, media=_WITH_MEDIUM),
    Rule("medium", "the order-2 smoothing energies vanish on the Euclidean squared distance only; use "
         "method='qclp' (or m=0) at order 2, or order=1", _QC_SMOOTHED, orders=(2,), media=_WITH_MEDIUM,
         smoothing=True),
    # coarse-to-fine
    Rule("multires", "multires applies to triangle meshes, not to tetrahedral ones", dims=(3,)),
    Rule("multires", "multires applies to the convex formulations, not to the baselines", BASELINE_METHODS),
    Rule("multires", "multires applies at order 1 (order=2 applies without multires)", orders=(2,)),
    Rule("multires", "cost and metric are not implemented with multires; solve on the mesh itself",
         media=_WITH_MEDIUM),
    Rule("multires", "multires takes vertex sources only; solve point, curve and boundary sources without "
         "multires", sources=("point", "curve", "boundary", "boundary faces")),
    # an adapted solve (resolution= other than "mesh": order 2 on a decimated copy, strategies/adapted.py)
    Rule("resolution", "resolution= decimates triangle meshes; tetrahedral meshes are solved on themselves",
         dims=(3,)),
    Rule("resolution", "resolution= solves at order 2, which the baselines do not have; give resolution='mesh'",
         BASELINE_METHODS),
    Rule("resolution", "resolution= solves at order 2, which the LC formulations do not have; use qclp or a qcqp "
         "method, or resolution='mesh'", _LC),
    Rule("resolution", "resolution= solves at order 2, which takes no curves; solve curves with resolution='mesh'",
         sources=("curve",)),
    # kinds of source
    Rule("source", "a SurfaceCurve lies on a surface; inside a volume give VolumePoints or BoundaryFaces",
         dims=(3,), sources=("curve",)),
    Rule("source", "BoundaryFaces are faces of a volume's boundary; on a surface give 'boundary' or a "
         "SurfaceCurve", dims=(2,), sources=("boundary faces",)),
    Rule("source", "potpourri3d's heat method takes vertex sources only", ("heat",), dims=(2,),
         sources=("point", "curve")),
    Rule("source", "solve curves at order 1", dims=(2,), orders=(2,), sources=("curve",)),
)
_AXES = ("method", "resolution", "order", "medium", "multires", "source")


def refusal(method: str, *, dim: int, order: int = 1, medium: str = "none", source: str | None = None,
            multires: bool = False, smoothing: bool = True, resolution: bool = False) -> Rule | None:
    """The first rule that refuses the cell (method rules first, then order, medium, multires, source), or None.

    Parameters
    ----------
    method : str
        A canonical name of :data:`METHODS`.
    dim : {2, 3}
    order : {1, 2}
    medium : {"none", "cost", "metric"}
    source : str, optional
        One of :data:`SOURCE_KINDS`; None: no source asked about.
    multires : bool
    smoothing : bool
        The solve has a smoothness term (``m > 0``); False lets the smoothed methods behave as their LP.
    resolution : bool
        An adapted solve (``resolution`` other than ``"mesh"``; it runs at order 2).
    """
    hits = [r for r in RULES if r.matches(method, dim, order, medium, source, multires, smoothing, resolution)]
    return min(hits, key=lambda r: _AXES.index(r.axis)) if hits else None


def supported(method: str, **cell) -> bool:
    """True when no rule refuses the cell (the arguments of :func:`refusal`)."""
    return refusal(method, **cell) is None


def methods_for(dim: int, order: int = 1, medium: str = "none", source: str | None = None, *,
                multires: bool = False, resolution: bool = False) -> tuple[str, ...]:
    """The methods that support a cell, in the order of :data:`METHODS` (a smoothed solve)."""
    return tuple(m for m in METHODS if supported(m, dim=dim, order=order, medium=medium, source=source,
                                                 multires=multires, resolution=resolution))


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


def check(method: str, *, dim: int, order: int = 1, medium: str = "none", sources: Iterable[str] = (),
          multires: bool = False, smoothing: bool = True, resolution: bool = False) -> None:
    """Raise the library's error when the table refuses the solve; the message says what is supported instead.

    Parameters
    ----------
    method : str
        A canonical name of :data:`METHODS` (aliases resolved, unknown names refused by the caller).
    dim, order, medium, multires, smoothing, resolution
        See :func:`refusal`.
    sources : iterable of str
        The kinds of source of one solve (:data:`SOURCE_KINDS`); empty when the solver is built.

    Raises
    ------
    ParameterError
        The method on this dimension, at this order, with this medium, with multires or with resolution.
    SourceError
        A kind of source the method cannot take there (the message names the methods that can).
    """
    cell: dict[str, Any] = {"dim": dim, "order": order, "medium": medium, "multires": multires,
                            "smoothing": smoothing, "resolution": resolution}
    rule = refusal(method, **cell)
    if rule is not None:
        raise ParameterError(_message(rule, method, **cell))
    refused = [(k, r) for k in SOURCE_KINDS if k in set(sources) and (r := refusal(method, source=k, **cell))]
    if refused:
        raise SourceError(_source_message(method, *refused[0], cell))


#: The point-cloud domain (:class:`~cvxgeodesic.mesh.pointcloud.PointCloud`, solved on the triangle soup of its local
#: fans): what it refuses beyond the triangle meshes' rules, as (axis, what, reason). docs/pointclouds.md.
CLOUD_REFUSALS: tuple[tuple[str, str, str], ...] = (
    ("method", "exact", "it needs a manifold surface; a cloud's triangles are overlapping fans, not one"),
    ("method", "fmm", "it needs a manifold surface; a cloud's triangles are overlapping fans, not one"),
    ("method", "lcqp-hessian", "the curved Hessian energy needs a consistently oriented surface; a cloud's "
     "overlapping fans have none (use qcqp-dirichlet or qcqp-laplacian for a smoothed field)"),
    ("method", "qcqp-hessian", "the curved Hessian energy needs a consistently oriented surface; a cloud's "
     "overlapping fans have none (use qcqp-dirichlet or qcqp-laplacian for a smoothed field)"),
    ("multires", "", "multires coarsens a mesh; solve a cloud on its own triangles"),
    ("resolution", "", "resolution= decimates a mesh; a cloud's triangles are a soup that quadric decimation does "
     "not keep; give resolution='mesh'"),
    ("source", "boundary", "a cloud's boundary is not detected (the fans' free edges are everywhere the fans "
     "disagree); give the boundary's points by index"),
    ("source", "curve", "curves are resampled on a manifold surface; give the curve's points by index or as "
     "SurfacePoints"),
)
#: The default method on a point cloud (docs/pointclouds.md: the most accurate on noisy clouds at about the
#: point-cloud heat method's cost).
CLOUD_DEFAULT_METHOD = "qclp"


def check_cloud(method: str, *, sources: Iterable[str] = (), multires: bool = False, resolution: bool = False) -> None:
    """Raise where :data:`CLOUD_REFUSALS` refuses the solve on a point cloud (after :func:`check` on triangles).

    Raises
    ------
    ParameterError
        The method, multires or resolution= on a cloud.
    SourceError
        A kind of source a cloud does not take.
    """
    kinds = set(sources)
    for axis, what, reason in CLOUD_REFUSALS:
        if axis == "method" and what == method:
            raise ParameterError(f"method {method!r} does not run on point clouds ({reason}); methods that do: "
                                 f"{', '.join(cloud_methods())}")
        if (axis == "multires" and multires) or (axis == "resolution" and resolution):
            raise ParameterError(f"{axis} on a point cloud: {reason}")
        if axis == "source" and what in kinds:
            raise SourceError(f"{what} sources on a point cloud: {reason}")


def cloud_methods() -> list[str]:
    """The methods that run on point clouds."""
    refused = {what for axis, what, _ in CLOUD_REFUSALS if axis == "method"}
    return [m for m in METHODS if m not in refused]


def _source_message(method: str, kind: str, rule: Rule, cell: dict[str, Any]) -> str:
    """The message of a refused kind of source, with every kind of the dimension refused for the same reason
    ("point or curve") and the methods that take it."""
    dim = cell["dim"]
    same = [k for k in SOURCE_KINDS if k == kind or (refusal(method, source=k, **cell) == rule
                                                     and methods_for(dim, source=k))]
    what = source_phrase(same)
    if rule.axis in ("multires", "resolution"):
        return f"{rule.axis}{'=' if rule.axis == 'resolution' else ''} cannot take {what} sources ({rule.reason})"
    can = [m for m in methods_for(dim, cell["order"], cell["medium"], kind, multires=cell["multires"],
                                  resolution=cell["resolution"]) if m != method]
    return (f"method {method!r} cannot take {what} sources {_ON[dim]}{' at order 2' if cell['order'] == 2 else ''} "
            f"({rule.reason}); " + (f"methods that can: {', '.join(can)}" if can else "no method can there"))


def _message(rule: Rule, method: str, *, dim: int, order: int, medium: str, multires: bool,
             smoothing: bool, resolution: bool = False) -> str:
    where = DIM_NAMES[dim]
    if rule.axis == "resolution":
        return f"resolution= is not available for method {method!r} on {where}: {rule.reason}"
    if rule.axis == "method":
        volume_or_surface = "on a volume" if dim == 3 else "on a surface"
        return (f"method {method!r} does not apply to {where} ({rule.reason}); {volume_or_surface} use one of "
                f"{', '.join(methods_for(dim))}")
    if rule.axis == "order":
        return (f"order={order} is implemented for {', '.join(methods_for(dim, order))} on {where}, not for "
                f"{method!r} ({rule.reason}; docs/order2.md)")
    if rule.axis == "medium":
        can = methods_for(dim, order, medium)
        at = f" at order {order}" + (" with m > 0" if rule.smoothing else "") if order != 1 else ""
        return (f"method {method!r} cannot take a travel cost or metric on {where}{at} ({rule.reason}); "
                + (f"methods that can: {', '.join(can)}" if can else "no method can there"))
    return f"multires is not available for method {method!r} on {where}: {rule.reason}"


# ---------------------------------------------------------------------------------------------------------------
# the table as text
# ---------------------------------------------------------------------------------------------------------------
_COLUMNS = ("order 1", "order 2", "cost, metric", "multires", "resolution", *SOURCE_KINDS)
#: What a column other than an order's asks of :func:`refusal` (a source column: its kind).
_COLUMN_CELLS: dict[str, dict[str, Any]] = {"cost, metric": {"medium": "cost"}, "multires": {"multires": True},
                                            "resolution": {"resolution": True}}


def _cell(method: str, dim: int, column: str, notes: dict[str, int]) -> str:
    """One cell of :func:`markdown_table`: "yes", "no [k]", or the orders / condition where it holds."""
    def note(rule: Rule) -> str:
        return f"[{notes.setdefault(rule.reason, len(notes) + 1)}]"

    rule = refusal(method, dim=dim)
    if rule is not None:  # the method does not apply to the dimension: said once, in its first column
        return f"no {note(rule)}" if column == "order 1" else "—"
    orders = [o for o in ORDERS if supported(method, dim=dim, order=o)]
    if column in ("order 1", "order 2"):
        rule = refusal(method, dim=dim, order=int(column[-1]))
        return "yes" if rule is None else f"no {note(rule)}"
    kw = _COLUMN_CELLS.get(column, {"source": column})
    verdicts = {o: (refusal(method, dim=dim, order=o, **kw), refusal(method, dim=dim, order=o, smoothing=False, **kw))
                for o in orders}
    if all(r is None for r, _ in verdicts.values()):
        return "yes"
    ok = [o for o, (r, _) in verdicts.items() if r is None]
    flat = [o for o, (r, r0) in verdicts.items() if r is not None and r0 is None]
    first = next(r for r, _ in verdicts.values() if r is not None)
    parts = [f"order {o}" for o in ok] + [f"order {o} with m = 0" for o in flat]
    return (f"{', '.join(parts)} {note(first)}" if parts else f"no {note(first)}")


def markdown_table() -> str:
    """The capability table as Markdown: one table per dimension, then the numbered reasons.

    ``docs/capabilities.md`` holds this text between its markers (a test checks that it is current).
    """
    notes: dict[str, int] = {}
    out = []
    for dim in DIMS:
        out += [f"## {DIM_NAMES[dim].capitalize()}", "",
                "| method | " + " | ".join(_COLUMNS) + " |", "|---" * (len(_COLUMNS) + 1) + "|"]
        out += [f"| `{m}` | " + " | ".join(_cell(m, dim, c, notes) for c in _COLUMNS) + " |" for m in METHODS]
        out.append("")
    out += ['—: the method does not apply to these meshes (its column "order 1" says why).', ""]
    for rule in RULES:  # the rules without a cell of their own (a method's dimension, multires' sources) close it
        notes.setdefault(rule.reason, len(notes) + 1)
    out += [f"{k}. {reason}" for reason, k in sorted(notes.items(), key=lambda kv: kv[1])]
    return "\n".join(out) + "\n"


def help_text() -> str:
    """A few lines for the command line's help: the methods, orders and media of each dimension."""
    lines = []
    for dim in DIMS:
        lines.append(f"{DIM_NAMES[dim]}: methods {', '.join(methods_for(dim))}; order 2: "
                     f"{', '.join(methods_for(dim, 2))}; cost/metric: "
                     f"{', '.join(methods_for(dim, 1, 'cost')) or 'none'}")
    return "\n".join(lines) + "\n(docs/capabilities.md has the whole table, sources included)"
