"""Exceptions raised at evoik_pin's boundary.

Every error names what was wrong and what is accepted. Each class subclasses the built-in exception a
Python user would expect (``ValueError``, ``KeyError``, ``FileNotFoundError``) so ``except ValueError``
keeps working, and :class:`EvoikError` so ``except EvoikError`` catches all of ours. :class:`RobotLoadWarning`
is the one warning: a URDF that loads with part of it ignored.
"""

from __future__ import annotations


class EvoikError(Exception):
    """Base class of every error evoik_pin raises on purpose."""


class _PlainMessage:
    """Prints its message as given: KeyError would quote it, FileNotFoundError and OSError print a tuple."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class RobotLoadError(EvoikError, ValueError):
    """A robot source could not be read or does not describe a usable robot (the message names the file)."""


class RobotLoadWarning(UserWarning):
    """A URDF loaded, but part of it was ignored: the warning names the file, the element and why (for example a
    ``<mimic>`` naming no joint of the file, whose joint is then loaded as an independent joint)."""


class RobotNotFoundError(_PlainMessage, EvoikError, FileNotFoundError):
    """A robot name or URDF path does not resolve to a file."""


class FrameError(_PlainMessage, EvoikError, KeyError):
    """A frame name the robot does not have (the message lists the closest names), or a goal's frame that no
    active joint moves."""


class LockedJointsError(FrameError):
    """A goal on a frame that only a floating base moves, while joints between the root and that frame are
    locked (off the robot's active joints): the base alone would have to reach it. The message names the locked
    joints and how to free them (``tips=[...]``, ``joints=[...]`` or ``tips="all"`` when loading)."""


class ConfigurationError(EvoikError, ValueError):
    """A joint vector or population has the wrong shape or non-finite entries."""


class BoundsError(EvoikError, ValueError):
    """Joint bounds are inverted, non-finite or of the wrong length."""


class TargetError(EvoikError, ValueError):
    """An IK target has the wrong shape, non-finite entries or a non-rotation matrix."""


class OptionError(EvoikError, ValueError):
    """A solver option is unknown or out of its accepted range."""


class ViewerError(EvoikError, RuntimeError):
    """The meshcat viewer could not start or reach its server, or could not write its HTML export."""


class MethodError(_PlainMessage, EvoikError, KeyError):
    """A solver method name is unknown or does not apply to this robot or call."""


class ReproductionError(EvoikError, ValueError):
    """A paper reproduction was asked for with an unknown paper id or an unusable option."""


class OutputError(_PlainMessage, EvoikError, OSError):
    """An output directory or file cannot be created or written."""


class SceneError(EvoikError, ValueError):
    """A collision scene that cannot be built or used: a bad obstacle (size, pose, mesh file), an unknown
    obstacle name, a scene file that does not parse, or a scene built for another robot."""


class BackendError(EvoikError, RuntimeError):
    """A compute backend that cannot be used: Ray not installed (``pip install 'evoik_pin[ray]'``), a cluster
    address that cannot be reached, or a chunk of work that failed on every attempt."""


class GoalsFileError(EvoikError, ValueError):
    """A goals file (:mod:`evoik_pin.io.goals_file`) that cannot be read or used: it does not parse, a goal has an
    unknown kind, a missing or bad field, or the file was written for another robot than the one it is used with.
    The message names the file, the goal (its index from 0, and its frame) and the field."""


class MotionError(EvoikError, ValueError):
    """A motion (:class:`evoik_pin.motion.Motion`) that cannot be made or used: keypoints of the wrong shape or
    with NaN/inf entries, an empty motion (no frame or no keypoint), duplicate keypoint names, an fps that is not a
    finite number > 0, a frame range or rate out of what the motion has. The message names the field and what is
    accepted."""


class BvhError(MotionError):
    """A BVH file that cannot be read: no ``HIERARCHY`` or ``MOTION`` section, a bad ``CHANNELS`` line, a frame
    whose value count differs from the hierarchy's channel count, a value that is not a number, a ``Frame Time``
    <= 0, an unknown unit. The message names the file and the line (from 1)."""


class MappingError(_PlainMessage, MotionError, KeyError):
    """A robot-to-motion keypoint mapping that cannot be used: an unknown preset, a robot frame absent from the
    robot or a keypoint absent from the motion (the message lists the closest names), or a robot without a
    floating base (load it with ``floating_base=True``)."""
