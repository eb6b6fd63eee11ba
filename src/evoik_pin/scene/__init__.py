"""Collision scenes: the robot's own body and obstacles around it (Pinocchio geometry models + coal).

* :mod:`.scene`: :class:`Scene` (obstacles; exact, batched and proxy collision checks; signed distance);
* :mod:`.geometry`: the robot's collision geometry, the pairs worth checking (adjacent and SRDF-disabled pairs
  left out), convex-hull proxies, pose checks;
* :mod:`evoik_pin.io.scene_file`: scene files (YAML / JSON obstacles), read by ``Scene.from_file`` and written by
  ``Scene.to_file``;
* :mod:`.examples`: example scenes (a table, an open shelf) and collision-free configurations.

With :mod:`evoik_pin.robot`, this is the only code that runs Pinocchio on a Model/Data.
"""

from .scene import Obstacle, Scene

__all__ = ["Obstacle", "Scene"]
