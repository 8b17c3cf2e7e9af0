"""The camera of the surface pictures (:mod:`cvxgeodesic.plotting`): which world axis is up, what ``view=`` means,
and the rotation of each panel.

A view is an ``(elev, azim)`` pair in degrees about the up axis (:func:`up_vector`), or a name: ``"front"``, facing
the first source (the picture code turns it until nothing hides the source), and ``"back"``, the front turned 180°
about up. For ``up = z`` the angles are matplotlib's ``mplot3d`` convention.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import ParameterError

__all__ = ["UP_NAMES", "VIEW_NAMES", "up_vector", "view_list"]


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v)
    return v / n if n > 0 else v


#: The named views of ``view=``: ``"front"`` faces the first marked source (without one, a 3/4 view of the mesh);
#: ``"back"`` is the same view turned 180° about the up axis, the far side of the field.
VIEW_NAMES = ("front", "back")
#: What ``up=`` takes besides a vector.
UP_NAMES = ("auto", "x", "y", "z", "-x", "-y", "-z")
_ELEV = 15.0  # degrees the default eye is raised above the horizontal
_TURN = 35.0  # degrees the view without a source turns away from the thinnest axis (a 3/4 view)
_MAX_PANELS = 4


def _is_pair(x: Any) -> bool:
    if isinstance(x, str):
        return False
    try:
        a = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError):
        return False
    return a.shape == (2,) and bool(np.all(np.isfinite(a)))


def view_list(view: Any) -> list[str | tuple[float, float]]:
    """The panels of ``view=``: each a name of :data:`VIEW_NAMES` or an ``(elev, azim)`` pair in degrees.

    ``None`` is ``["front", "back"]``; a name or a pair is one panel; a list of them, one panel each (at most 4).

    Raises
    ------
    ParameterError
        Anything else (the message names ``view``).
    """
    if view is None:
        return list(VIEW_NAMES)
    items = [view] if isinstance(view, str) or _is_pair(view) else view
    bad = ParameterError(f"view must be 'front', 'back', (elev, azim) in finite degrees or a list of them, got "
                         f"{view!r}")
    try:
        items = list(items)
    except TypeError:
        raise bad from None
    out: list[str | tuple[float, float]] = []
    for item in items:
        if isinstance(item, str) and item.strip().lower() in VIEW_NAMES:
            out.append(item.strip().lower())
        elif _is_pair(item):
            out.append((float(item[0]), float(item[1])))
        else:
            raise bad
    if not 1 <= len(out) <= _MAX_PANELS:
        raise ParameterError(f"view: give 1 to {_MAX_PANELS} views, got {len(out)}")
    return out


def _snapped_axes(V: np.ndarray) -> list[np.ndarray]:
    """The principal axes of the vertices, largest variance first, each snapped to a distinct world axis
    (scanned models are usually axis-aligned)."""
    X = V - V.mean(axis=0)
    _, U = np.linalg.eigh(X.T @ X)
    snapped, free = [], [0, 1, 2]
    for ax_i in U[:, ::-1].T:
        j = max(free, key=lambda k: abs(ax_i[k]))
        free.remove(j)
        snapped.append(np.eye(3)[j])
    return snapped


def up_vector(V: np.ndarray, up: Any = "auto") -> np.ndarray:
    """The world direction drawn upwards on screen: a (3,) unit vector.

    ``up`` is a name of :data:`UP_NAMES` or a (3,) vector. ``"auto"`` (:func:`_auto_up`) looks for what the model
    stands on: of the two world axes across its thinnest principal axis, the one whose end carries a flat face of the
    convex hull (feet, hooves, a base: at least 2 % of the hull's area within 5° of facing down that axis, 1.5 times
    what the other axis carries) points up, away from that end. A model without such a support (a bust, a sphere)
    gets world ``+y`` (the convention of OBJ and glTF files), or ``+z`` where ``y`` is the thinnest axis. On the
    shared scans this stands bunny, armadillo, spot, lucy and kitten on ``+y`` and horse, buddha and dragon on ``+z``;
    no rule of this kind is always right: give ``up`` when it is not.

    Raises
    ------
    ParameterError
        An unknown name, or a vector that is not three finite numbers of non-zero length.
    """
    if isinstance(up, str):
        name = up.strip().lower()
        if name == "auto":
            return _auto_up(V)
        if name in UP_NAMES:
            return (-1.0 if name[0] == "-" else 1.0) * np.eye(3)["xyz".index(name[-1])]
        raise ParameterError(f"up must be one of {', '.join(UP_NAMES)} or a 3-vector, got {up!r}")
    try:
        u = np.asarray(up, dtype=np.float64)
    except (TypeError, ValueError):
        u = np.empty(0)
    if u.shape != (3,) or not np.all(np.isfinite(u)) or not np.linalg.norm(u) > 0:
        raise ParameterError(f"up must be one of {', '.join(UP_NAMES)} or a 3-vector, got {up!r}")
    return u / np.linalg.norm(u)


def _auto_up(V: np.ndarray) -> np.ndarray:
    """``up="auto"`` (:func:`up_vector`): away from the axis-aligned end the convex hull stands on, else ``+y``."""
    axes = _snapped_axes(V)
    fallback = np.eye(3)[2] if axes[2][1] == 1.0 else np.eye(3)[1]
    support = {}
    try:
        from scipy.spatial import ConvexHull

        hull = ConvexHull(V)
    except Exception:  # flat or degenerate point sets (qhull refuses them): no support to find
        return fallback
    P = V[hull.simplices]
    area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    normals = hull.equations[:, :3]  # outward, unit
    for ax in axes[:2]:
        k = int(np.argmax(ax))
        for sign in (1.0, -1.0):
            support[k, sign] = area[sign * normals[:, k] > np.cos(np.radians(5.0))].sum() / area.sum()
    (k, sign), best = max(support.items(), key=lambda kv: kv[1])
    other = max(v for (j, _), v in support.items() if j != k)
    if best < 0.02 or best < 1.5 * other:
        return fallback
    return -sign * np.eye(3)[k]  # away from the end it stands on


def _frame(up: np.ndarray) -> np.ndarray:
    """Rows ``e1, e2, up``, right-handed: ``azim`` turns from ``e1`` towards ``e2`` about ``up``. For ``up = z`` this is
    ``x, y, z`` (matplotlib's ``mplot3d``); for ``y``: ``z, x, y``; for ``x``: ``y, z, x``."""
    k = int(np.argmax(np.abs(up)))
    ref = np.eye(3)[(k + 1) % 3]
    e1 = _unit(ref - (ref @ up) * up)
    return np.vstack([e1, np.cross(up, e1), up])


def _angles(d: np.ndarray, frame: np.ndarray) -> tuple[float, float]:
    """``(elev, azim)`` in degrees of the direction ``d`` in ``frame``."""
    x, y, z = frame @ _unit(d)
    return float(np.degrees(np.arcsin(np.clip(z, -1.0, 1.0)))), float(np.degrees(np.arctan2(y, x)) % 360.0)


def _rotation(elev: float, azim: float, frame: np.ndarray) -> np.ndarray:
    """Rows: screen right, screen up, direction towards the viewer (orthonormal, right-handed)."""
    e, a = np.radians(elev), np.radians(azim)
    e1, e2, up = frame
    horizontal = np.cos(a) * e1 + np.sin(a) * e2
    toward = np.cos(e) * horizontal + np.sin(e) * up
    world_up = up
    if abs(np.sin(e)) > 0.999:  # looking straight down or up: screen up along -azim (or +azim)
        world_up = -np.sign(np.sin(e)) * horizontal
    right = _unit(np.cross(world_up, toward))
    return np.vstack([right, np.cross(toward, right), toward])


def _front_angles(V: np.ndarray, frame: np.ndarray, focus: np.ndarray | None) -> tuple[float, float]:
    """``(elev, azim)`` of the ``"front"`` view: facing the unit normal ``focus``, or without one a 3/4 view.

    Facing ``focus``: its azimuth, its elevation clamped to [-60°, 60°] and raised to 15° when it is flatter.
    Without: looking along the thinnest principal axis across ``up`` (from its positive side), turned 35° sideways,
    the eye raised 15°.
    """
    across = [a for a in _snapped_axes(V) if abs(a @ frame[2]) < 0.5]  # the axes across up, largest first
    azim = _angles(across[-1] if across else frame[0], frame)[1] + _TURN
    if focus is None:
        return _ELEV, azim % 360.0
    elev, az = _angles(focus, frame)
    if np.hypot(focus @ frame[0], focus @ frame[1]) > 0.05:  # else straight up or down: keep the 3/4 azimuth
        azim = az
    elev = float(np.clip(elev, -60.0, 60.0))
    return (_ELEV if abs(elev) < _ELEV else elev), azim % 360.0


def _camera(V: np.ndarray, view: Any, focus: np.ndarray | None = None, *, up: Any = "auto") -> np.ndarray:
    """Rows: screen right, screen up, direction towards the viewer, of one panel (orthonormal, right-handed).

    ``view`` is None or ``"front"`` (facing the unit normal ``focus`` when given), ``"back"`` (the front turned
    180° about ``up``) or ``(elev, azim)`` in degrees about ``up`` (:func:`up_vector`, :func:`_frame`).
    """
    frame = _frame(up_vector(V, up))
    return _rotation(*_view_angles(V, view, frame, focus), frame)


def _view_angles(V, view, frame, focus) -> tuple[float, float]:
    spec = view_list(view)[0] if view is not None else "front"
    if not isinstance(spec, str):
        return spec
    elev, azim = _front_angles(V, frame, focus)
    return (elev, azim) if spec == "front" else (elev, (azim + 180.0) % 360.0)
