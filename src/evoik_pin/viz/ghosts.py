"""Ghosts: several configurations drawn at once as translucent robots, one colour each (``<name>/<k>``).

Ghosts reuse the robot drawing (:mod:`.robot`) with one colour and an opacity per node, Collada meshes loaded as
plain geometry so the colour applies; past :data:`GHOST_MESH_BUDGET` bytes of embedded mesh files they are drawn
as skeletons.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..errors import ConfigurationError
from .robot import skeleton_model
from .server import _talks

__all__ = ["GHOST_COLORS", "GHOST_MESH_BUDGET"]

#: Ghost colours (RGB in [0, 1]), used in turn by :meth:`Viewer.show_solutions`.
GHOST_COLORS: tuple[tuple[float, float, float], ...] = (
    (0.12, 0.47, 0.71), (1.00, 0.50, 0.05), (0.17, 0.63, 0.17), (0.84, 0.15, 0.16), (0.58, 0.40, 0.74),
    (0.55, 0.34, 0.29), (0.89, 0.47, 0.76), (0.50, 0.50, 0.50), (0.74, 0.74, 0.13), (0.09, 0.75, 0.81),
)
#: Most bytes of mesh files :meth:`Viewer.show_solutions` embeds for its ghosts before it draws skeletons.
GHOST_MESH_BUDGET = 50_000_000


class GhostDrawing:
    """The Viewer's ghost groups."""

    @_talks
    def show_solutions(self, solutions, name: str = "solutions", opacity: float = 0.4, limit: int = 64,
                       style: str = "auto") -> list[str]:
        """Draw several configurations at once as translucent ghost robots, one colour each.

        Args:
            solutions: a list of joint vectors (n,) or of results with a ``.q``, an (N, n) array, or an
                object whose ``.q`` is (N, n) (e.g. a Pareto front) or that has ``.solutions``.
            name: group node; ghost k is ``<name>/<k>`` (a checkbox each in the browser). Drawing the same
                name again replaces the group.
            opacity: ghost opacity in (0, 1].
            limit: at most this many ghosts (evenly spaced, with a warning, when there are more).
            style: ``"mesh"`` (the robot's own visuals), ``"skeleton"`` (spheres and cylinders), or
                ``"auto"``: meshes unless the ghosts' mesh files would exceed :data:`GHOST_MESH_BUDGET`
                bytes in all (every ghost embeds a copy: 11 MB of mesh files per Panda).

        Returns:
            The ghosts' node names.

        Raises:
            ConfigurationError: no configuration to draw, e.g. the empty list :func:`evoik_pin.solve_all` returns
                for an unreachable target (the error quotes that list's ``message``: why it is empty).
        """
        empty = getattr(solutions, "solutions", solutions)
        if isinstance(empty, list) and not empty:
            why = getattr(solutions, "message", "")
            raise ConfigurationError("show_solutions: no configurations given (an empty list of solutions)"
                                     + (f": {why}" if why else ""))
        Q = self._qs(solutions)
        name = name.strip("/")
        if not name or not 0.0 < opacity <= 1.0 or limit < 1 or style not in ("auto", "mesh", "skeleton"):
            raise ConfigurationError(
                f"show_solutions needs a non-empty name, 0 < opacity <= 1, limit >= 1 and style 'auto', 'mesh' or "
                f"'skeleton'; got name={name!r}, opacity={opacity}, limit={limit}, style={style!r}"
            )
        if Q.shape[0] > limit:
            keep = np.unique(np.linspace(0, Q.shape[0] - 1, limit).round().astype(int))
            warnings.warn(f"{Q.shape[0]} solutions: drawing {keep.size} of them (limit={limit})", UserWarning,
                          stacklevel=3)
            Q = Q[keep]
        if style == "auto":
            style = "skeleton" if Q.shape[0] * self._mesh_bytes() > GHOST_MESH_BUDGET else "mesh"
        geom = None
        if style == "skeleton" and not self.skeleton:
            if self._skeleton_geom is None:
                self._skeleton_geom = skeleton_model(self.robot)
            geom = self._skeleton_geom
        self.delete(name)
        nodes = []
        for k, q in enumerate(Q):
            node = f"{name}/{k}"
            rgba = (*GHOST_COLORS[k % len(GHOST_COLORS)], opacity)
            self._load(node, rgba, geom).display(self.robot.to_pinocchio(q))
            self.scene[node] = "ghost skeleton" if style == "skeleton" else "ghost"
            nodes.append(node)
        return nodes
