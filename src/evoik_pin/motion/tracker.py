"""A control loop's IK: :class:`Tracker`, one warm-started solve per step inside the velocity limits.

Teleoperation, servoing and whole-body control call IK at control rate (1 kHz for an arm, several hundred Hz for a
humanoid) with goals that move a little every step. A :class:`Tracker` keeps the robot's last configuration and an
:class:`~evoik_pin.IKSolver` made once (options checked, goal stacks and LM engines cached); each :meth:`Tracker.step`
runs Levenberg-Marquardt from the last configuration inside its velocity box ``[q - v_max dt, q + v_max dt]``
(:meth:`~evoik_pin.IKSolver.solve_within`); after the first step of a goal structure (its frames, kinds, weights and
tolerances; or a tip pose or position) the next ones of that structure take the solver's prepared step
(:mod:`evoik_pin.solvers.search.box_step`: the new targets and box written into the engine's own arrays, one
compiled run, the same answers; a miss goes on in the stage's search). The answer never leaves the box, so
the commanded motion respects the robot's speed limits whatever the goals do; goals out of reach for one step give
the answer closest to them inside the box and ``success=False``, and the loop catches up on the next steps.

Example::

    tracker = ek.Tracker(panda, dt=0.001, q0=q_now)
    for T in targets:                 # one per control period
        r = tracker.step(T)           # a Result; r.q within v_max dt of the last q
        send(r.q)
"""

from __future__ import annotations

import numpy as np

from ..call_setup import _rng
from ..ik_solver import IKSolver
from ..robot.velocity_limits import check_dt
from ..robot.velocity_limits import velocity_limits as limits_of

__all__ = ["Tracker"]


class Tracker:
    """One warm-started IK solve per control step, inside the robot's velocity limits.

    Args:
        robot: a :class:`~evoik_pin.Robot` or anything :func:`~evoik_pin.load_robot` accepts.
        dt: the control period (s, > 0).
        q0: (n,) the robot's configuration now (rad or m): the first step's box is around it.
        velocity_limits: ``True`` (the URDF's, defaults where it has none), a factor > 0 of those, or an array (n,)
            of speeds (rad/s, m/s); a floating base's x, y, z in m/s and yaw, pitch, roll as Euler rates in rad/s
            (:mod:`evoik_pin.robot.velocity_limits`).
        seed: int, Generator or None: draws the extra starts of a step whose run from the last configuration falls
            short (the same seed, the same answers).
        **options: the :class:`~evoik_pin.IKSolver`'s (``tolerance`` m, ``rotation_tolerance`` rad, ``bounds``,
            ``scene``, ``margin`` m, ``locked``, ...), checked here, once.

    Raises:
        OptionError: a bad ``dt`` or ``velocity_limits``; ConfigurationError: a bad ``q0``; the IKSolver's errors for
        bad options.
    """

    def __init__(self, robot, dt: float, q0, velocity_limits=True, seed=None, **options) -> None:
        self.dt = check_dt(dt)
        self._solver = IKSolver(robot, **options)
        self.robot = robot = self._solver.robot
        self.velocity_limits = limits_of(robot, velocity_limits)
        self._step = self.velocity_limits * self.dt
        self._rng = _rng(seed)
        self._q = np.array(robot.check_q(q0), dtype=float)  # a float64 vector of our own: the compiled run's type

    @property
    def q(self) -> np.ndarray:
        """(n,) the last configuration (rad or m): ``q0``, then each step's answer (a copy)."""
        return self._q.copy()

    @property
    def max_step(self) -> np.ndarray:
        """(n,) the largest change per step of each entry of q, ``v_max dt`` (rad or m) (a copy)."""
        return self._step.copy()

    def reset(self, q) -> None:
        """Restart from the configuration ``q`` (n,) (rad or m), e.g. after the robot was moved by hand."""
        self._q = np.array(self.robot.check_q(q), dtype=float)

    def step(self, goals):
        """One control step towards ``goals``: a target of the tip (position (3,) m, ``pin.SE3``, (4, 4)) or a goal
        list (:mod:`evoik_pin.goals`). Returns the :class:`~evoik_pin.Result`; its ``q`` (n,) lies within
        ``v_max dt`` of the last configuration, which it becomes (also when ``success`` is False: the closest the
        robot can get this step)."""
        result = self._solver._within(goals, self._q, self._step, self._rng)  # q, step and rng checked
        self._q = result.q.copy()
        return result

    def __repr__(self) -> str:
        return f"Tracker({self.robot.name!r}, dt={self.dt:g})"
