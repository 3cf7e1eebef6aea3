"""Roles and records shared by the plant, estimators, controllers and the mission.

Controllers, estimators and the mission import this module, never :mod:`tetherland.sim`,
so that each can run against the simulation or against a real vehicle.

Data flow of one run (chapter Fig. 6.3, section 6.6.4)::

    IMU 1 kHz ──► Estimator.predict ─┐
    mocap 120 Hz ► Estimator.update ─┴► Estimator.estimate() ─► StateEstimate
    StateEstimate ─► ReferenceSource.reference(t, est) ─► Reference   (the supervisor)
    (t, StateEstimate, Reference) ─► Controller.update ─► Command     (500 Hz, rotor speeds)

Conventions: SI units, vectors in F_W unless the name says otherwise, quaternions
scalar-first (w, x, y, z), body frame FLU with z_B the thrust axis. Every record is a
frozen dataclass; arrays inside records must not be modified after construction.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import IntEnum
from types import MappingProxyType
from typing import Protocol, runtime_checkable

import numpy as np

from tetherland.geometry import FloatArray
from tetherland.records import fast_init
from tetherland.state import LinkState, RigidBodyState

_EMPTY: Mapping[str, float] = MappingProxyType({})


def _no_diagnostics() -> Mapping[str, float]:
    return _EMPTY


@fast_init
@dataclass(frozen=True, slots=True)
class ImuSample:
    """One IMU reading (strapdown, body frame).

    Attributes
    ----------
    t : float
        Sample time [s].
    specific_force_B : (3,) array
        Specific force a - g in F_B (at rest on level ground it reads +g z_B) [m/s^2].
    omega_B : (3,) array
        Angular rate in F_B [rad/s].
    """

    t: float
    specific_force_B: FloatArray
    omega_B: FloatArray


@fast_init
@dataclass(frozen=True, slots=True)
class MocapSample:
    """One motion-capture pose of the body, delivered after a latency.

    Attributes
    ----------
    t_measured : float
        Instant the pose refers to [s].
    t_delivered : float
        Instant the sample reaches the estimator, t_measured + latency [s].
    p_W : (3,) array
        Position of the centre of mass [m]; NaN when ``valid`` is False.
    q_WB : (4,) array
        Attitude (w, x, y, z), F_B -> F_W; NaN when ``valid`` is False.
    valid : bool
        False during a dropout (the tracker lost the body).
    """

    t_measured: float
    t_delivered: float
    p_W: FloatArray
    q_WB: FloatArray
    valid: bool = True


@fast_init
@dataclass(frozen=True, slots=True)
class StateEstimate:
    """What an estimator knows at time ``t``.

    Attributes
    ----------
    t : float
        Time of the estimate [s].
    body : RigidBodyState
        Position, velocity, attitude and body rate of the centre of mass.
    gyro_bias_B, accel_bias_B : (3,) array or None
        Estimated IMU biases in F_B [rad/s], [m/s^2].
    covariance : (n, n) array or None
        Error covariance in the estimator's own error-state ordering (documented by it).
    link : LinkState or None
        Estimated link angles (phi, delta) and rates, when tethered [rad, rad/s].
    tension : float or None
        Estimated cable tension f_L [N].
    external_force_B : (3,) array or None
        Estimated non-rotor force on the vehicle in F_B, m (f_B - b_a) - f_R e3 (cable,
        surface contact, wind) [N].
    """

    t: float
    body: RigidBodyState
    gyro_bias_B: FloatArray | None = None
    accel_bias_B: FloatArray | None = None
    covariance: FloatArray | None = None
    link: LinkState | None = None
    tension: float | None = None
    external_force_B: FloatArray | None = None


class ControlMode(IntEnum):
    """Which controller the supervisor wants active (chapter 6.6.3)."""

    FREE_FLIGHT = 0
    """Position and attitude control without the cable (approach, hooking, stretching)."""
    TETHERED = 1
    """Tethered output tracking of y^b = [phi, delta, theta_A, psi] (Gamma_HC^b or DFL)."""
    MOTORS_OFF = 2
    """Rotors commanded to zero speed (landed, deploying: t_G to t_T)."""


@fast_init
@dataclass(frozen=True, slots=True)
class Feedforward:
    """Nominal values along a planned tethered trajectory (flatness), for feed-forward.

    Attributes
    ----------
    omega_B, omega_dot_B : (3,) arrays
        Nominal angular velocity [rad/s] and acceleration [rad/s^2] in the nominal F_B.
    f_R, f_R_dot, f_R_ddot : float
        Nominal total thrust and its derivatives [N, N/s, N/s^2].
    tension : float
        Nominal cable tension [N].
    """

    omega_B: FloatArray
    omega_dot_B: FloatArray
    f_R: float
    f_R_dot: float = 0.0
    f_R_ddot: float = 0.0
    tension: float = 0.0


@fast_init
@dataclass(frozen=True, slots=True)
class Reference:
    """What the supervisor asks of the controller at time ``t``.

    Attributes
    ----------
    t : float
        Time the reference is for [s].
    mode : ControlMode
        Which control law applies.
    phase : int
        Mission phase code (defined by the mission; logged as is) [-].
    p_W : (k, 3) array or None
        Desired position and its first k-1 time derivatives as rows (p, v, a, ...) [m, m/s, ...].
    yaw : float
        Desired heading psi [rad].
    output : (k, 4) array or None
        Tethered output y^b = [phi, delta, theta_A, psi] and its first k-1 derivatives as rows
        (the DFL controller needs k = 5) [rad, rad/s, ...].
    thrust_ff : float or None
        Nominal total thrust f_R from the planner [N].
    feedforward : Feedforward or None
        Nominal angular velocity, thrust and tension of a planned tethered trajectory.
    terminate : bool
        True when the supervisor has finished; the runner stops after this tick.
    lateral_free : bool
        Tethered: leave the link azimuth delta to gravity, with no sideways force but a
        fraction of the damping of delta' (the supervisor's lateral release in the last centimetres,
        ``mission.touchdown.lateral_clearance``). The hierarchical controller honours it;
        the DFL controller tracks ``output`` as given.
    lean_limit : float
        Tethered: the largest lean of the desired thrust axis out of the link plane,
        atan(|u_y| / sqrt(u_x^2 + u_z^2)) in F_L [rad]; the sideways force u_y is cut to it
        and the delta integral stops growing meanwhile (the supervisor's lean limit at the
        landing, ``mission.touchdown.lean_limit_deg``). 0: no limit. The hierarchical
        controller honours it; the DFL controller tracks ``output`` as given.
    thrust_scale : float
        Every rotor thrust the controller commands is multiplied by this, 0 to 1 (rotor
        speeds by its square root, the wanted thrust and torque by it) [-]: the
        supervisor's spin-down on the surface before the motors go off
        (``mission.touchdown.spin_down_time``); 1 in flight.
    thrust_shed : float
        This fraction of the commanded total thrust, 0 to 1, is taken off every rotor
        equally before ``thrust_scale`` applies, the torques kept [-]: the supervisor's
        preload from the first sign of contact (``mission.touchdown.preload``); 0 in
        flight.
    drag_in_rows : bool
        Free flight: the ``p_W`` rows from the acceleration on are the thrust's,
        f_R z_B / m - g z_W, and its derivatives, from a plan whose model has the believed
        rotor drag (the drag of the planned motion and its rates are already in them), so
        the rotor-drag feed-forward (:mod:`tetherland.control.rotor_drag`) leaves them as
        they are; False: the rows are the flat outputs' (p and its derivatives).
    torque_ff_B : (3,) array or None
        A known body torque the controller adds to the one its law asks for, F_B [N m]:
        the moment of a weight the vehicle carries off the body origin, where the
        controllers put the centre of mass (the magnet mechanism's: its centre of mass
        moves when the magnet leaves the boom, :func:`tetherland.models.hook.magnet_load`).
        None: nothing added.
    """

    t: float
    mode: ControlMode = ControlMode.FREE_FLIGHT
    phase: int = 0
    p_W: FloatArray | None = None
    yaw: float = 0.0
    output: FloatArray | None = None
    thrust_ff: float | None = None
    feedforward: Feedforward | None = None
    terminate: bool = False
    lateral_free: bool = False
    lean_limit: float = 0.0
    thrust_scale: float = 1.0
    thrust_shed: float = 0.0
    drag_in_rows: bool = False
    torque_ff_B: FloatArray | None = None


@fast_init
@dataclass(frozen=True, slots=True)
class Command:
    """What a controller sends to the ESCs (chapter 6.6.4) and what it meant by it.

    Attributes
    ----------
    rotor_speeds : (4,) array
        Commanded spinning speed of each rotor, in the rotor order of
        :class:`tetherland.models.RotorLayout` [rad/s]. Zero switches a motor off.
    thrust : float or None
        Total thrust f_R the controller wanted [N].
    torque_B : (3,) array or None
        Body torque the controller wanted, F_B [N m].
    diagnostics : mapping of str to float
        Extra named scalars (errors, gains in use, singularity margins) for the log.
    """

    rotor_speeds: FloatArray
    thrust: float | None = None
    torque_B: FloatArray | None = None
    diagnostics: Mapping[str, float] = field(default_factory=_no_diagnostics)

    @classmethod
    def motors_off(cls) -> Command:
        """All rotors stopped."""
        return cls(rotor_speeds=np.zeros(4), thrust=0.0, torque_B=np.zeros(3))


@dataclass(frozen=True, slots=True)
class EventRecord:
    """Something that happened during a run, for the log (phase switches, faults, hooks).

    Attributes
    ----------
    t : float
        When [s].
    source : str
        Who reports it (``"mission"``, ``"hook"``, ``"runner"``, ...).
    kind : str
        Short machine-readable name (``"phase"``, ``"abort"``, ``"ENGAGED"``, ...).
    message : str
        Human-readable reason.
    """

    t: float
    source: str
    kind: str
    message: str = ""

    def as_dict(self) -> dict[str, object]:
        return {"t": self.t, "source": self.source, "kind": self.kind, "message": self.message}


@runtime_checkable
class EventSource(Protocol):
    """Optional capability of a reference source (the supervisor): events for the run log."""

    @property
    def events(self) -> list[EventRecord]:
        """Every event so far, in time order."""
        ...


@runtime_checkable
class Estimator(Protocol):
    """State estimator: IMU as process input, motion capture as measurement (section 8)."""

    def predict(self, imu: ImuSample) -> None:
        """Propagate the state to ``imu.t`` with one IMU sample (1 kHz)."""
        ...

    def update(self, mocap: MocapSample) -> None:
        """Fuse one delayed motion-capture sample (check ``mocap.valid``)."""
        ...

    def estimate(self) -> StateEstimate:
        """The current estimate (after the last predict/update)."""
        ...


@runtime_checkable
class ImuBatchAware(Protocol):
    """Optional estimator capability: IMU samples handed over as rows, several at once.

    The runner then collects the samples of its physics steps as rows [t, f_B (3),
    omega_B (3)] and hands them over before each motion-capture update and each estimate,
    in the order taken, instead of one :meth:`Estimator.predict` per sample (without
    building an :class:`ImuSample` for each: the loop's cost, issue 25)."""

    def predict_rows(self, rows: FloatArray) -> None:
        """The same as :meth:`Estimator.predict` of ``ImuSample(r[0], r[1:4], r[4:7])`` for
        each row ``r`` of ``rows`` (n, 7), in order [s, m/s^2, rad/s]."""
        ...


@runtime_checkable
class CommandAware(Protocol):
    """Optional estimator or reference-source capability: told each command sent (e.g. for
    tension estimation, or the supervisor's fault monitor)."""

    def command_sent(self, t: float, command: Command) -> None:
        """``command`` is applied from time ``t`` on."""
        ...


@runtime_checkable
class Controller(Protocol):
    """Maps the estimate and the reference to rotor speed commands (500 Hz)."""

    def update(self, t: float, estimate: StateEstimate, reference: Reference) -> Command:
        """Compute the command held until the next control tick."""
        ...


@runtime_checkable
class InnerLoop(Protocol):
    """A flight controller between the controller and the ESCs (e.g. Betaflight firmware).

    The controller's command becomes its setpoint; the inner loop runs at the IMU rate on
    what the IMU measures and commands the rotors itself (the runner holds its output).
    """

    def start(self) -> None:
        """A run begins (power on): before the first sample."""
        ...

    def setpoint(
        self, t: float, estimate: StateEstimate, reference: Reference, command: Command
    ) -> None:
        """The controller's ``command`` at control tick ``t``, with what it was made from."""
        ...

    def step(self, imu: ImuSample) -> FloatArray:
        """One loop on an IMU sample: rotor speed commands held from the next tick [rad/s]."""
        ...

    def applied(self, command: Command) -> Command:
        """What the rotors are being commanded now (the inner loop's output, as motor
        telemetry), for the roles told of each command sent (``CommandAware``)."""
        ...

    def stop(self) -> None:
        """The run is over (also after a failure): release everything."""
        ...


@runtime_checkable
class MagnetCommander(Protocol):
    """Optional reference-source capability: the robot's commands to an electro-permanent
    magnet it carries and to the latch of the clip that holds it on its boom (the magnet
    mechanism, docs/mechanism.md), read by the runner at every control tick."""

    @property
    def magnet_on(self) -> bool:
        """True: the magnet switched on (held), False: off (released)."""
        ...

    @property
    def latch_open(self) -> bool:
        """True: the latch of the clip that holds the magnet on its boom opened (the clip
        lets the magnet go), False: closed."""
        ...


@runtime_checkable
class ReferenceSource(Protocol):
    """The supervisor (issue 6): chooses the mode and the reference from the estimate."""

    def reference(self, t: float, estimate: StateEstimate) -> Reference:
        """Reference for time ``t``; may switch phases based on ``estimate``."""
        ...


__all__ = [
    "Command",
    "CommandAware",
    "ControlMode",
    "Controller",
    "Estimator",
    "EventRecord",
    "EventSource",
    "Feedforward",
    "ImuSample",
    "InnerLoop",
    "MagnetCommander",
    "MocapSample",
    "Reference",
    "ReferenceSource",
    "StateEstimate",
]
