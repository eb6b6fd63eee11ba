"""Imported by docs_zygote's fork server only (never by a test): what every documented command needs before its own
work, done once for all of them: evoik_pin and its command line imported, one solve (the LM kernel and memetic's first
runs for pose, position and planar goals loaded from numba's disk cache, or compiled there if the cache is cold)."""

import numpy as np

import evoik_pin
import evoik_pin.cli  # noqa: F401 - imported for the forks

_robot = evoik_pin.load_robot("ur5")
evoik_pin.solve(_robot, _robot.fk(_robot.random_configurations(1, np.random.default_rng(0))[0]), seed=0)
del _robot
