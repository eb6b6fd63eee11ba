"""Collision scenes: the robot's own body and obstacles around it (Pinocchio geometry models + coal): :class:`Scene`,
the robot's geometry and pairs (:mod:`.geometry`), example scenes (:mod:`.examples`)."""

from .scene import Obstacle, Scene

__all__ = ["Obstacle", "Scene"]
