"""Ghosts: several configurations drawn at once as translucent robots, one colour each (``<name>/<k>``)."""

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
        """Draw configurations (any form :class:`~evoik_pin.viz.Viewer` takes) as translucent ghosts ``<name>/<k>``,
        one colour each, at most ``limit`` (evenly spaced, with a warning); return their node names.

        ``style``: ``"mesh"``, ``"skeleton"``, or ``"auto"``: meshes unless the ghosts' mesh files exceed
        :data:`GHOST_MESH_BUDGET` bytes in all (each ghost embeds a copy). ConfigurationError for nothing to draw
        (quoting an empty :func:`evoik_pin.solve_all` list's ``message``)."""
        empty = getattr(solutions, "solutions", solutions)
        if isinstance(empty, list) and not empty:
            why = getattr(solutions, "message", "")
            raise ConfigurationError("show_solutions: no configurations given (an empty list of solutions)"
                                     + (f": {why}" if why else ""))
        Q = self._qs(solutions)
        name = name.strip("/")
        if not name or not 0.0 < opacity <= 1.0 or limit < 1 or style not in ("auto", "mesh", "skeleton"):
            raise ConfigurationError(f"show_solutions needs a non-empty name, 0 < opacity <= 1, limit >= 1 and style "
                                     f"'auto', 'mesh' or 'skeleton'; got name={name!r}, opacity={opacity}, "
                                     f"limit={limit}, style={style!r}")
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
        for k, q in enumerate(Q):
            rgba = (*GHOST_COLORS[k % len(GHOST_COLORS)], opacity)
            self._load(f"{name}/{k}", rgba, geom).display(self.robot.to_pinocchio(q))
            self.scene[f"{name}/{k}"] = "ghost skeleton" if style == "skeleton" else "ghost"
        return [f"{name}/{k}" for k in range(Q.shape[0])]
