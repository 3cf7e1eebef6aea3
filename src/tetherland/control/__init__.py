"""Controllers: free flight (geometric position + SO(3) attitude), tethered, switching."""

from tetherland.control.attitude import AttitudeController, AttitudeGains, attitude_error
from tetherland.control.position import PositionController, PositionReference, WrenchCommand

__all__ = [
    "AttitudeController",
    "AttitudeGains",
    "PositionController",
    "PositionReference",
    "WrenchCommand",
    "attitude_error",
]
