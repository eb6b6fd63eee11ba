"""CenterOfMass: the whole robot's centre of mass at a point, or its ground projection over a support polygon."""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import FrameError, GoalsFileError, OptionError, TargetError
from ..io.datafile import Flow, floats, naming
from .file_entries import FileKind, field_entries, number, position_target, unknown_keys
from .goal import DEFAULT_GOAL_TOLERANCE, Goal, point3
from .goal import number as goal_number
from .registry import COM_POINT, COM_SUPPORT, FAMILY_BEYOND_FRAME, KindCode

__all__ = ["A_COM_AXES", "A_COM_BODIES", "A_COM_MASS", "A_COM_MOMENT", "A_COM_POINTS", "A_COM_SHRINK", "KIND_COM",
           "KIND_COM_SUPPORT", "CenterOfMass", "com_of", "contact_points", "polygon_distance"]

#: The kernel codes of the centre of mass at a point on chosen axes (3 rows, the others zeroed) and of its ground
#: projection inside a support polygon (2 rows).
KIND_COM, KIND_COM_SUPPORT = COM_POINT, COM_SUPPORT
#: Their ``aux`` row (read by the compiled ``solvers/lm/balance.py``): total mass M (kg), the first moment (kg m, base
#: frame) of the bodies no joint moves, the axes mask (1.0 on the constrained axes; KIND_COM) or (KIND_COM_SUPPORT)
#: the shrink s (m) of the support polygon and its number K of contact points; then A_COM_BODIES + 5 k (k < m):
#: physical joint k's body mass m_k (kg), first moment m_k c_k (kg m, in the joint's folded frame) and the mass of
#: its whole subtree (kg); then, for KIND_COM_SUPPORT, A_COM_BODIES + 5 m + 4 i: contact point i's physical joint
#: (-1: none) and its position (m) in that joint's folded frame (in the base frame for -1).
A_COM_MASS, A_COM_MOMENT, A_COM_AXES, A_COM_SHRINK, A_COM_POINTS, A_COM_BODIES = 0, 1, 4, 4, 5, 7

_AXES = "xyz"


@dataclass(frozen=True, eq=False, repr=False)
class CenterOfMass(Goal):
    """The robot's centre of mass (masses from the URDF's inertias) at a point, or its ground projection inside a
    support polygon. Exactly one of:

    * ``point``: a 3-vector (m, base frame), met on ``axes`` (any of "x", "y", "z", default "xyz": ``axes="xy"``
      puts the CoM above the point) when the distance over them is within ``tolerance`` (m).
    * ``support``: ``{frame: points}`` (a (k, 3) array, m, in that frame: the corners of a sole), or a list of
      frames whose contact points come from their collision geometry (:func:`contact_points`). The CoM's ground
      (x, y) projection lies inside the convex hull of the contact points', at least ``margin`` (m, >= 0) inside each
      edge (the solver aims ``tolerance`` further in); its error is the distance (m) outside, 0 inside.

    Args (all by keyword): point, axes, support, margin, then ``weight`` (> 0, default 1) and ``tolerance`` (m,
    default 1e-6).
    """

    point: np.ndarray | None = None
    axes: str = _AXES
    support: dict | None = None
    margin: float = 0.0
    KIND_CODES = (KindCode(KIND_COM, (0, 1, 2), FAMILY_BEYOND_FRAME),
                  KindCode(KIND_COM_SUPPORT, (0, 1), FAMILY_BEYOND_FRAME))

    def __init__(self, point=None, axes: str = _AXES, support=None, margin: float = 0.0, weight: float = 1.0,
                 tolerance: float = DEFAULT_GOAL_TOLERANCE) -> None:
        if (point is None) == (support is None):
            raise TargetError("CenterOfMass takes a point (point=p, a 3-vector in m) or a support polygon "
                              "(support={frame: points} or support=[frames]), exactly one of the two")
        kind = KIND_COM if support is None else KIND_COM_SUPPORT
        self._init_common(None, weight, tolerance, None, kind, False, "the centre-of-mass goal")
        if support is None:
            if not isinstance(axes, str) or not axes or not set(axes) <= set(_AXES) or len(set(axes)) != len(axes):
                raise OptionError(f"CenterOfMass's axes name each of x, y, z at most once (e.g. 'xyz', 'xy', 'z'), "
                                  f"got {axes!r}")
            self._set(point=point3(point, "CenterOfMass's point"), axes="".join(a for a in _AXES if a in axes),
                      support=None, margin=0.0)
        else:
            self._set(point=None, axes="xy", support=_support(support), margin=goal_number(
                margin, "margin (m) of the centre-of-mass support goal", "a finite number >= 0", 0.0))

    @property
    def frames(self) -> list[str]:
        """The support frames (none for a point)."""
        return list(self.support or ())

    label = "center of mass"  # how messages name this goal (it has no frame)

    def encode(self) -> tuple[np.ndarray, np.ndarray]:
        return (np.zeros(3) if self.point is None else self.point.copy()), np.eye(3)

    def pack(self, robot) -> tuple[np.ndarray, np.ndarray]:
        """(aux row, support row (m,) bool) of this goal on ``robot`` (the ``A_COM_*`` layout). TargetError for a robot
        without mass, FrameError for an unknown support frame or one without geometry."""
        mc = robot.mass_constants
        if not mc.total > 0.0:
            raise TargetError(f"{robot.name} has no mass (its URDF gives its links no inertial mass): a "
                              "CenterOfMass goal needs the links' masses")
        m = robot.tree.m
        points = []  # per contact point its physical joint (-1: none), its position (m) in that joint's folded frame
        for frame, pts in [] if self.support is None else _frame_points(robot, self.support):
            j, R, p = robot.frame_constants(frame)  # FrameError with the closest names
            points += [[j, *(R @ x + p)] for x in pts]
        aux = np.zeros(A_COM_BODIES + 5 * m + 4 * len(points))
        aux[A_COM_MASS] = mc.total
        aux[A_COM_MOMENT:A_COM_MOMENT + 3] = mc.fixed_moment
        body = aux[A_COM_BODIES:A_COM_BODIES + 5 * m].reshape(m, 5)
        body[:, 0], body[:, 1:4], body[:, 4] = mc.masses, mc.moments, mc.subtree
        if self.support is None:
            aux[A_COM_AXES:A_COM_AXES + 3] = [1.0 if a in self.axes else 0.0 for a in _AXES]
        else:
            aux[A_COM_SHRINK] = self.margin + self.tolerance
            aux[A_COM_POINTS] = len(points)
            aux[A_COM_BODIES + 5 * m:] = np.ravel(points)
        return aux, mc.subtree > 0.0

    def marker(self) -> tuple[str, np.ndarray, None] | None:
        """A sphere at the point (node ``center_of_mass``); None for a support polygon."""
        return None if self.point is None else ("center_of_mass", self.point.copy(), None)

    @classmethod
    def file_kind(cls) -> FileKind:
        """``kind: center_of_mass`` (no frame): ``target: {position}`` (m) with optional ``axes``, or ``support:``
        ({frame: [[x, y, z], ...]} in each frame, m, or [frames]) with optional ``margin`` (m)."""
        return FileKind("center_of_mass", cls, (), position_target, _file_entry, read=_file_goal, write=_file_entry)

    def batch_key(self) -> tuple:
        """What this goal's kernel numbers depend on besides its target point."""
        if self.support is None:
            return (self.axes,)
        return (self.margin, *((f, None if p is None else p.tobytes()) for f, p in self.support.items()))

    def _axes_distance(self, c: np.ndarray) -> np.ndarray:
        """The distances (m) over ``axes`` from centres of mass c (..., 3) to the point."""
        return np.linalg.norm((c - self.point)[..., np.array([a in self.axes for a in _AXES])], axis=-1)

    def _ground(self, robot, Q: np.ndarray) -> np.ndarray:
        """(N, K, 2) the contact points' ground (x, y) positions (m, base frame) over a population Q (N, n)."""
        frames = _frame_points(robot, self.support)
        P, R = robot.fk_batch(Q, validate=False, frames=[f for f, _ in frames])
        return np.concatenate([np.einsum("nij,kj->nki", R[:, g], pts) + P[:, g, None] for g, (_, pts)
                               in enumerate(frames)], axis=1)[:, :, :2]

    def robot_errors(self, robot, q) -> tuple[float, None]:
        """(error m, None) at ``q`` (n,), the centre of mass from Pinocchio's ``centerOfMass``."""
        c = com_of(robot, q)
        if self.support is None:
            return float(self._axes_distance(c)), None
        return polygon_distance(c[:2], self._ground(robot, np.asarray(q, dtype=float)[None])[0], self.margin), None

    def robot_population_errors(self, robot, Q) -> tuple[np.ndarray, np.ndarray]:
        """(errors (N,) m, zeros (N,)) of a population Q (N, n); for a support polygon the largest violation of the
        margin-shrunk hull's edge half-planes (0 exactly inside; at most the distance outside)."""
        c = com_batch(robot, Q)
        if self.support is None:
            return self._axes_distance(c), np.zeros(len(Q))
        return _hull_violation(c[:, :2], self._ground(robot, Q), self.margin), np.zeros(len(Q))

    def __repr__(self) -> str:
        where = (f"point={np.round(self.point, 6).tolist()}, axes={self.axes!r}" if self.support is None
                 else f"support={self.frames}, margin={self.margin:g}")
        return f"CenterOfMass({where}, weight={self.weight:g}, tolerance={self.tolerance:g})"


def _support(support) -> dict:
    """{frame: (k, 3) points or None (from the collision geometry)} of a support argument, checked."""
    if isinstance(support, (list, tuple)):
        support = dict.fromkeys(support)
    if not isinstance(support, dict):
        raise TargetError(f"CenterOfMass's support is {{frame: points (k x 3, m)}} or a list of frames, got "
                          f"{type(support).__name__}")
    if not support:
        raise TargetError("CenterOfMass's support names no frame: give {frame: points (k x 3, m)} or [frames]")
    out = {}
    for frame, pts in support.items():
        if not isinstance(frame, str) or not frame:
            raise FrameError(f"CenterOfMass's support frames are frame names (strings), got {frame!r}")
        if pts is not None:
            try:
                a = np.array(pts, dtype=float)
            except (TypeError, ValueError):
                a = np.zeros((0, 0))
            a = a[None] if a.shape == (3,) else a
            if a.ndim != 2 or a.shape[1] != 3 or a.shape[0] == 0 or not np.isfinite(a).all():
                raise TargetError(f"support points of {frame!r} are a k x 3 array (m) of finite numbers with k >= 1, "
                                  f"got {pts!r}")
            pts = a
        out[frame] = pts
    return out


def contact_points(robot, frame: str) -> np.ndarray:
    """(4, 3) contact points (m, in ``frame``): the four corners of the lowest face (least z in the frame) of the box,
    aligned with the frame's axes, that bounds every collision geometry on the frame's joint (a sole frame, z up:
    the foot's bottom). Raises FrameError when the frame's joint carries no collision geometry."""
    known = _CONTACTS.setdefault(robot, {})
    if frame in known:  # read the geometry once: every solve binds its goals and reports their errors
        return known[frame].copy()
    f = robot.model.frames[robot.frame_id(frame)]
    fMj = f.placement.inverse()
    corners = []
    for g in robot.collision_model.geometryObjects:
        if g.parentJoint != f.parentJoint:
            continue
        shape = g.geometry
        shape.computeLocalAABB()
        lo, hi = np.asarray(shape.aabb_local.min_), np.asarray(shape.aabb_local.max_)
        box = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
        M = fMj * g.placement
        corners.append(box @ np.asarray(M.rotation).T + np.asarray(M.translation))
    if not corners:
        raise FrameError(f"frame {frame!r} of {robot.name} carries no collision geometry to take contact points "
                         f"from: give its points, support={{{frame!r}: points (k x 3, m)}}")
    c = np.concatenate(corners)
    (x0, y0, z), (x1, y1, _) = c.min(axis=0), c.max(axis=0)
    known[frame] = np.array([[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]])
    return known[frame].copy()


#: Contact points from collision geometry, per robot (weakly: the cache keeps no robot alive) and frame.
_CONTACTS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _frame_points(robot, support: dict) -> list[tuple[str, np.ndarray]]:
    """(frame, its (k, 3) points in it) of each support frame (collision geometry where none were given)."""
    return [(f, contact_points(robot, f) if pts is None else pts) for f, pts in support.items()]


def com_of(robot, q) -> np.ndarray:
    """The robot's centre of mass (m, base frame) at ``q`` (n,), Pinocchio's ``centerOfMass`` of the whole URDF
    (:attr:`~evoik_pin.robot.Robot.full_model` at ``full_configuration(q)``)."""
    data = _FULL_DATA.get(robot)
    if data is None:
        data = _FULL_DATA[robot] = robot.full_model.createData()
    c = pin.centerOfMass(robot.full_model, data, robot.full_configuration(q))
    return robot.tree.base_R @ c + robot.tree.base_p


#: Pinocchio data of each robot's full model (weakly: the cache keeps no robot alive).
_FULL_DATA: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def com_batch(robot, Q) -> np.ndarray:
    """Centres of mass (N, 3) (m, base frame) of a population Q (N, n), from the folded tree's joint poses and the
    :attr:`Robot.mass_constants`."""
    parent, FR, Fp, rev = robot.tree_constants()[:4]
    mc = robot.mass_constants
    X = robot._physical(np.asarray(Q, dtype=float))
    N, m = X.shape[0], parent.size
    Rj, pj = np.empty((m, N, 3, 3)), np.empty((m, N, 3))
    total = np.broadcast_to(mc.fixed_moment, (N, 3)).copy()
    for k in range(m):
        a = parent[k]
        if a < 0:
            R, p = np.broadcast_to(FR[k], (N, 3, 3)).copy(), np.broadcast_to(Fp[k], (N, 3)).copy()
        else:
            R, p = Rj[a] @ FR[k], pj[a] + Rj[a] @ Fp[k]
        x = X[:, k]
        if rev[k]:
            c, s = np.cos(x)[:, None], np.sin(x)[:, None]
            R[:, :, 0], R[:, :, 1] = c * R[:, :, 0] + s * R[:, :, 1], c * R[:, :, 1] - s * R[:, :, 0]
        else:
            p = p + x[:, None] * R[:, :, 2]
        Rj[k], pj[k] = R, p
        total += mc.masses[k] * p + R @ mc.moments[k]
    return total / mc.total


def _hull_violation(c: np.ndarray, ground: np.ndarray, margin: float) -> np.ndarray:
    """Largest violation (N,) (m, >= 0) of the point c (N, 2) against the edge half-planes of the convex hull of
    each row's points ground (N, K, 2) shrunk by ``margin``: an edge i -> j has every point on its left."""
    d = ground[:, None, :, :] - ground[:, :, None, :]  # (N, K, K, 2): p_j - p_i
    L = np.linalg.norm(d, axis=3)
    with np.errstate(invalid="ignore", divide="ignore"):
        n = np.stack([d[..., 1], -d[..., 0]], axis=3) / L[..., None]  # outward (right-hand) unit normals
    rel = ground[:, None, None, :, :] - ground[:, :, None, None, :]  # (N, K, 1, K, 2): p_l - p_i
    side = np.einsum("nijd,nikld->nijl", n, np.broadcast_to(rel, rel.shape))
    edge = (L > 1e-12) & (side <= 1e-12).all(axis=3)
    v = np.einsum("nijd,nid->nij", n, c[:, None, :] - ground) + margin
    v = np.where(edge, v, -np.inf).max(axis=(1, 2))
    return np.where(np.isfinite(v), np.maximum(v, 0.0), np.inf)


def polygon_distance(point, points, margin: float = 0.0) -> float:
    """Distance (m) from ``point`` (2,) to the convex hull of ``points`` (K, >= 2) (their x, y) shrunk by
    ``margin`` (m): 0 inside; inf when the shrunk hull is empty or the points span no area."""
    # exact: the nearest of the feet on the shrunk edges' lines and of their crossings that lie in it
    from scipy.spatial import ConvexHull, QhullError

    try:  # the hull's edges: n.x <= o inside, n unit outward
        hull = ConvexHull(np.asarray(points, dtype=float)[:, :2]).equations
    except (QhullError, ValueError):  # points spanning no area
        return float("inf")
    normals, b = hull[:, :2], -hull[:, 2] - margin
    c = np.asarray(point, dtype=float)
    if (normals @ c <= b).all():
        return 0.0
    slack = 1e-12 * (1.0 + np.abs(b).max())
    candidates = [c - (normals[i] @ c - b[i]) * normals[i] for i in range(len(b))]
    for i in range(len(b)):
        for j in range(i + 1, len(b)):
            A = np.array([normals[i], normals[j]])
            if abs(np.linalg.det(A)) > 1e-12:
                candidates.append(np.linalg.solve(A, [b[i], b[j]]))
    inside = [x for x in candidates if (normals @ x <= b + slack).all()]
    if not inside:
        return float("inf")
    return float(min(np.linalg.norm(x - c) for x in inside))


def _file_goal(entry: dict, what: str) -> CenterOfMass:
    """A ``kind: center_of_mass`` entry of a goals file (:meth:`CenterOfMass.file_kind`)."""
    unknown_keys(entry, ("kind", "target", "axes", "support", "margin", "weight", "tolerance"),
                 f"{what}, a center_of_mass goal (it has no frame)")
    options = {key: number(entry[key], f"{what}: {key}") for key in ("weight", "tolerance", "margin")
               if key in entry}
    with naming(what, GoalsFileError, catch=(OptionError, TargetError, FrameError)):
        if "target" in entry:
            if not isinstance(entry["target"], dict):
                raise GoalsFileError(f"target must be a mapping (position), got {entry['target']!r}")
            return CenterOfMass(point=position_target(entry["target"]), axes=entry.get("axes", _AXES), **options)
        if "support" not in entry:
            raise GoalsFileError("a center_of_mass goal needs target: {position: [x, y, z]} (m) or support: "
                                 "{frame: [[x, y, z], ...]} or [frames]")
        return CenterOfMass(support=entry["support"], **options)


def _file_entry(goal: CenterOfMass) -> dict:
    """A centre-of-mass goal as a goals file writes it."""
    entry: dict = {"kind": "center_of_mass"}
    if goal.support is None:
        entry["target"] = Flow(position=floats(goal.point))
        entry["axes"] = goal.axes
    else:
        given = {f: p for f, p in goal.support.items() if p is not None}
        entry["support"] = ({f: [floats(row) for row in given.get(f, [])] for f in goal.support}
                            if given else list(goal.support))
        if goal.margin:
            entry["margin"] = float(goal.margin)
    return entry | field_entries(goal, ("weight", "tolerance"))
