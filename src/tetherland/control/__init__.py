"""Controllers: free flight (geometric position + SO(3) attitude), tethered hierarchical
Gamma_HC^b and dynamic-feedback-linearising Gamma_DFL^b, and bumpless switching."""

from tetherland.control.attitude import AttitudeController, AttitudeGains, attitude_error
from tetherland.control.dfl import DflController
from tetherland.control.free_flight import FreeFlightController
from tetherland.control.hierarchical import HierarchicalController
from tetherland.control.mixer import Mixer
from tetherland.control.position import PositionController, PositionReference, WrenchCommand
from tetherland.control.switching import SwitchingController, SwitchRecord, make_tethered_controller

__all__ = [
    "AttitudeController",
    "AttitudeGains",
    "DflController",
    "FreeFlightController",
    "HierarchicalController",
    "Mixer",
    "PositionController",
    "PositionReference",
    "SwitchRecord",
    "SwitchingController",
    "WrenchCommand",
    "attitude_error",
    "make_tethered_controller",
]
