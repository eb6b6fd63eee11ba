"""Stepping back out of self-collision: the farthest collision-free configuration on the way from a free one to a
colliding one, for a retargeted frame whose answer collides.

Why not a scene-aware solve: the solvers judge collisions on the answers that meet every goal (a scene rejects a
converged answer that collides), and a retargeting frame's goals usually conflict a little (limb directions against
held feet), so its answer never converges and the scene never steers it. Stepping back along the segment
``q_prev -> q`` keeps what is known: ``q_prev`` is collision-free and inside the velocity box, so is every point of
the segment (the box is convex), and a check decides: with the retargeter's check, the convex hulls of the pairs
the stepping joints move (a point they call apart is apart for the meshes too; microseconds a test, where a mesh test
a hair from a contact costs ~1 ms on G1), the exact meshes for the other pairs.

``scene`` below is anything with ``in_collision(q)`` and ``colliding_pairs(q)``: a :class:`~evoik_pin.Scene` or
the retargeter's :class:`~evoik_pin.motion.self_collision_check.SelfCollisionCheck` (the same verdicts, cheaper;
its ``surely_free`` lets a bisection decide on the convex hulls, its ``touching_pair`` names the pair it found).
"""

from __future__ import annotations

import functools

import numpy as np

__all__ = ["BISECTION_RESOLUTION", "BISECTION_STEPS", "free_nearby", "step_back_free"]

#: Bisection steps on the segment at most (the last free point within 2^-8 of the segment's length of the contact).
BISECTION_STEPS = 8
#: The bisection stops once the interval left moves no entry of q more than this (rad or m): a step back then gives
#: up at most 0.05 rad (5 cm) of the colliding joints' motion in that frame (the next frame takes it up again), and
#: skips the last checks. 0.01 before (docs/BENCHMARKS.md, "The step back's resolution": the last checks were mesh
#: tests a hair apart, ~1 ms each on G1; the hulls' now cost microseconds); 0.03 and 0.05 measured on walk, run, jump
#: x G1, Talos: every group's mean limb angle within 0.3 degrees of 0.01's.
BISECTION_RESOLUTION = 5e-2
#: Colliding pairs whose links' joints step back together at most (the second attempt).
MAX_PAIRS = 4


def _farthest_free(scene, q_from: np.ndarray, q_to: np.ndarray, joints: np.ndarray, beat: float = -1.0
                   ) -> tuple[float, np.ndarray]:
    """The largest t in [0, 1] (bisection, to :data:`BISECTION_RESOLUTION`) with ``q_to`` but ``joints`` (bool (n,))
    at ``q_from + t (q_to - q_from)`` collision-free (with a check that has ``surely_free``: free on the hulls of the
    pairs the joints move, t = 0 when those touch at the start), and that configuration; (-1, q_to) when even t = 0
    collides.
    ``beat``: the t another side already found; once the bisection's upper end is at or below it this side cannot
    find more, and it stops there (its t, then at most ``beat``, loses the comparison it was made for; a side that can
    beat it is bisected in full)."""

    def at(t: float) -> np.ndarray:
        return np.where(joints, q_from + t * (q_to - q_from), q_to)

    # with the retargeter's check, the pairs these joints move are bisected on their hulls (no mesh test: the
    # dearest near a contact, ~1 ms on G1), so the point found is free as the meshes say (each mesh inside its hull),
    # a little before they would touch; when the hulls already touch at t = 0 (a hand by the hip: the hulls of two
    # concave links) the step stays at t = 0, the start, if that is free
    surely_free = getattr(scene, "surely_free", None)
    if surely_free is None:  # a Scene: its exact verdicts
        if scene.in_collision(at(0.0)):
            return -1.0, q_to
        collides = scene.in_collision
    elif surely_free(at(0.0), joints):
        def collides(q: np.ndarray) -> bool:  # the pairs the joints do not move: as at t = 0, apart
            return not surely_free(q, joints, others_free=True)
    elif scene.in_collision(at(0.0)):
        return -1.0, q_to
    else:
        return 0.0, at(0.0)
    span = float(np.max(np.abs(q_to - q_from), where=joints, initial=0.0))  # the most a moving entry travels
    lo, hi = 0.0, 1.0
    for _ in range(BISECTION_STEPS):
        if hi <= beat or (hi - lo) * span <= BISECTION_RESOLUTION:
            break
        mid = 0.5 * (lo + hi)
        if collides(at(mid)):
            hi = mid
        else:
            lo = mid
    return lo, at(lo)


@functools.lru_cache(maxsize=512)
def _joints_moving(robot, link: str, others: str) -> np.ndarray:
    """bool (n,): the entries of q that move ``link`` but not ``others`` (a floating base moves both: never); kept
    per robot and pair of links (a clip asks for the same few pairs every colliding frame), read-only."""
    try:
        mine, theirs = set(robot.moving_joints(link)), set(robot.moving_joints(others))
    except Exception:  # a geometry name that is no frame: no joint known to move it alone
        out = np.zeros(robot.n, dtype=bool)
    else:
        out = np.array([name in mine and name not in theirs for name in robot.joint_names])
    out.setflags(write=False)
    return out


def step_back_free(robot, scene, q_prev: np.ndarray, q: np.ndarray, keep: np.ndarray | None = None
                   ) -> np.ndarray | None:
    """A collision-free configuration between collision-free ``q_prev`` and colliding ``q`` (n,), as near ``q`` as
    bisection finds: the joints moving only one link of a colliding pair (the check's :meth:`touching_pair` when it
    has one, else the scene's first) step back towards ``q_prev`` (the side that keeps more of the step; the checks
    cover every pair), else the joints moving only either link of any colliding pair, else the whole configuration.
    ``keep`` (bool (n,)): joints that do not step back (those placing a held foot: an arm gives way before a stance
    leg); when nothing else frees the pair, the answer is ``q_prev`` itself (interpolating a leg's joints would slide
    its foot). None when ``q_prev`` itself collides."""
    movable = np.ones(robot.n, dtype=bool) if keep is None else ~np.asarray(keep, dtype=bool)
    if scene.in_collision(q_prev):
        return None
    q = np.asarray(q, dtype=float)
    # one colliding pair alone (the one the check found: the narrow phase of the others only if its links' joints do
    # not free it)
    first = (scene.touching_pair(q) if hasattr(scene, "touching_pair")
             else next(iter(scene.colliding_pairs(q)), None))
    if first is None:
        return q.copy()
    a, b = first
    sides = [_joints_moving(robot, link, other) & movable for link, other in ((a, b), (b, a))]
    if keep is not None and np.any(keep) and not (sides[0].any() or sides[1].any()):
        # no joint that may step back moves one link of the pair and not the other (a stance leg against the
        # pelvis): every step keeps this contact, and the answer is q_prev (below, after every pair's narrow phase)
        return np.array(q_prev, dtype=float)
    best_t, best_q = -1.0, None
    for joints in sides:
        if joints.any():
            t, candidate = _farthest_free(scene, q_prev, q, joints, best_t)
            if t > best_t:
                best_t, best_q = t, candidate
    if best_q is not None and best_t >= 0:
        return best_q
    either = np.zeros(robot.n, dtype=bool)
    for a, b in scene.colliding_pairs(q, most=MAX_PAIRS):
        either |= _joints_moving(robot, a, b) | _joints_moving(robot, b, a)
    either &= movable
    if either.any():
        t, candidate = _farthest_free(scene, q_prev, q, either)
        if t >= 0:
            return candidate
    if keep is not None and np.any(keep):  # stepping the joints of a held foot back would slide it: no step
        return np.array(q_prev, dtype=float)
    return _farthest_free(scene, q_prev, q, np.ones(robot.n, dtype=bool))[1]


#: Random draws of :func:`free_nearby` per spread, and its spreads (rad, m) around the colliding configuration.
NEARBY_DRAWS = 16
NEARBY_SPREADS = (0.05, 0.1, 0.2, 0.4, 0.8)


def free_nearby(robot, scene, q: np.ndarray, lower: np.ndarray, upper: np.ndarray, rng: np.random.Generator,
                keep: np.ndarray | None = None) -> np.ndarray | None:
    """A collision-free configuration near colliding ``q`` (n,), inside [lower, upper], for :func:`step_back_free`
    to step from when no free previous frame exists (a clip's first frame): the joints moving only one link of a
    colliding pair (less ``keep``) drawn around ``q`` with a widening normal spread (:data:`NEARBY_DRAWS` a spread),
    the free draw nearest ``q`` at the first spread that has one. None when no draw is free (at once, without a
    draw, when a colliding pair has no drawn joint moving one link and not the other: a stance leg against the
    pelvis, whose contact every draw keeps)."""
    kept = np.zeros(robot.n, dtype=bool) if keep is None else np.asarray(keep, dtype=bool)

    def apart(a: str, b: str) -> np.ndarray:
        return (_joints_moving(robot, a, b) | _joints_moving(robot, b, a)) & ~kept

    found = scene.touching_pair(q) if hasattr(scene, "touching_pair") else None
    if found is not None and not apart(*found).any():
        return None  # told before the other pairs' narrow phase
    movable = np.zeros(robot.n, dtype=bool)
    for a, b in scene.colliding_pairs(q):
        joints = apart(a, b)
        if not joints.any():
            return None
        movable |= joints
    for spread in NEARBY_SPREADS:
        draws = np.minimum(np.maximum(np.where(movable, q + rng.normal(0.0, spread, (NEARBY_DRAWS, robot.n)), q),
                                      lower), upper)
        # the nearest free draw: the draws checked nearest first (a stable sort: equally near ones in draw order)
        distance = [float(np.linalg.norm(d - q)) for d in draws]
        for k in sorted(range(len(draws)), key=distance.__getitem__):
            if not scene.in_collision(draws[k]):
                return draws[k]
    return None
