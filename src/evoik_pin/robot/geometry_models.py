"""A robot's visual and collision geometry (:class:`RobotGeometry`, a base class of :class:`~evoik_pin.robot.Robot`)."""

from __future__ import annotations

import re
from functools import cached_property
from pathlib import Path

import pinocchio as pin

from ..errors import RobotLoadError
from .frames import reduced_model
from .packages import MESH_URI

__all__ = ["RobotGeometry"]


class RobotGeometry:
    """The URDF's visual and collision models reduced like the robot's model, and their placements."""

    @property
    def base_placement(self) -> pin.SE3:
        """Placement (m, a new ``pin.SE3``) of the base frame in :attr:`model`'s world frame (constant)."""
        return self._oMbase.copy()

    def geometry_placements(self, geometry_model: pin.GeometryModel, q) -> list[pin.SE3]:
        """Placements (new ``pin.SE3``, m, :attr:`model`'s world frame) of the objects of ``geometry_model`` on
        :attr:`model`'s joints at ``q`` (n,)."""
        q = self.check_q(q)
        gdata = pin.GeometryData(geometry_model)
        pin.forwardKinematics(self.model, self.data, self.to_pinocchio(q))
        pin.updateGeometryPlacements(self.model, self.data, geometry_model, gdata)
        return [M.copy() for M in gdata.oMg]

    @cached_property
    def visual_model(self) -> pin.GeometryModel:
        """Visual geometry on :attr:`model`'s joints, for the viewer."""
        return self._geometry_model(pin.GeometryType.VISUAL)

    @cached_property
    def collision_model(self) -> pin.GeometryModel:
        """Collision geometry (``<collision>``) on :attr:`model`'s joints, for :class:`~evoik_pin.scene.Scene`."""
        return self._geometry_model(pin.GeometryType.COLLISION)

    def _geometry_model(self, kind) -> pin.GeometryModel:
        """The URDF's geometry of one kind, reduced onto :attr:`model`."""
        if self.urdf_xml is None:  # pragma: no cover
            raise RobotLoadError("this robot has no URDF text to read geometry from")
        xml = MESH_URI.sub(self._mesh_file, self.urdf_xml) if self.packages else self.urdf_xml
        try:
            geom = pin.buildGeomFromUrdfString(self._kin_model, xml, kind, package_dirs=self.package_dirs)
        except (ValueError, RuntimeError) as exc:  # a mesh Pinocchio could not find or read
            said = str(exc).strip()
            why = [m for pkg, m in self.missing_packages.items() if f"package://{pkg}/" in said]
            raise RobotLoadError(f"{self.name}: {why[0] if why else said}") from None
        return reduced_model(self._kin_model, self._locked, self._q_ref_full, (geom,))[1][0] if self._locked else geom

    def _mesh_file(self, m: re.Match) -> str:
        """The file of a ``package://pkg/rel`` URI whose package was found, else the URI (for ``package_dirs``)."""
        folder = self.packages.get(m.group(1))
        if folder is not None and (Path(folder) / m.group(2)).is_file():
            return (Path(folder) / m.group(2)).as_posix()
        return m.group(0)
