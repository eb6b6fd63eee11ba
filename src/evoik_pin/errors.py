"""Exceptions raised at evoik_pin's boundary: each subclasses :class:`EvoikError` and the built-in exception a Python
user would expect (``ValueError``, ``KeyError``, ...); :class:`RobotLoadWarning` is the one warning."""

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
    """A URDF loaded with part of it ignored (e.g. a ``<mimic>`` naming no joint): the file, the element and why."""


class RobotNotFoundError(_PlainMessage, EvoikError, FileNotFoundError):
    """A robot name or URDF path does not resolve to a file."""


class FrameError(_PlainMessage, EvoikError, KeyError):
    """A frame name the robot does not have (the message lists the closest names), or a goal's frame that no
    active joint moves."""


class LockedJointsError(FrameError):
    """A goal on a frame only a floating base moves while joints between the root and it are locked (not active);
    the message names them and how to free them."""


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
    """A collision scene that cannot be built or used: a bad obstacle or scene file, one built for another robot."""


class BackendError(EvoikError, RuntimeError):
    """A compute backend that cannot be used: Ray not installed, a cluster out of reach, a chunk failing every try."""


class GoalsFileError(EvoikError, ValueError):
    """A goals file (:mod:`evoik_pin.io.goals_file`) that cannot be read or used; the message names the file, the goal
    (index and frame) and the field."""


class MotionError(EvoikError, ValueError):
    """A motion (:class:`evoik_pin.motion.Motion`) that cannot be made or used (bad keypoints, fps, frame range); the
    message names the field and what is accepted."""


class BvhError(MotionError):
    """A BVH file that cannot be read; the message names the file and the line (from 1)."""


class MappingError(_PlainMessage, MotionError, KeyError):
    """A robot-to-motion keypoint mapping that cannot be used: an unknown preset, frame or keypoint (the closest names
    listed), or a robot without a floating base."""
