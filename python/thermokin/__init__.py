"""thermokin: thermal error compensation and sim-to-real diagnosis for serial industrial robots.

The extended forward geometric model (same-orientation joint frames, each joint with three
translations, one rotation and six error parameters), FK / Jacobian / IK one configuration or a batch,
compensation by IK on the deformed model, and the diagnosis of where a measured robot and its model
disagree. Units are the command line's: millimetres and degrees; arrays are ``float64``.

>>> import thermokin
>>> robot = thermokin.Robot.from_file("configs/irb140.toml")   # doctest: +SKIP
>>> robot.fk([0, 30, 10, 0, -40, 0]).shape                     # doctest: +SKIP
(4, 4)
"""

from thermokin._native import (
    Compensation,
    IKResult,
    Measurements,
    Plan,
    Report,
    Robot,
    compensate,
    diagnose,
    plan,
    pose_to_xyz_euler,
    simulate,
)
from thermokin.errors import InputError, MissingFileError, RefusedError, ThermokinError

__all__ = [
    "Compensation",
    "IKResult",
    "InputError",
    "Measurements",
    "MissingFileError",
    "Plan",
    "RefusedError",
    "Report",
    "Robot",
    "ThermokinError",
    "compensate",
    "diagnose",
    "plan",
    "pose_to_xyz_euler",
    "simulate",
]
