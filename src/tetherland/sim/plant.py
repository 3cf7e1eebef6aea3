"""The physics plant: MuJoCo scene, rotors behind their ESCs, cable and hook.

Rotor model (docs/theory.md section 4, chapter 6.6.4): the input is the commanded spinning speed
of each rotor (the ESC interface). Each speed follows a first-order lag with time constant
tau_m, integrated exactly for a command held over the step,
w_{k+1} = w_cmd + (w_k - w_cmd) exp(-dt / tau_m), and rotor i pushes f_i = c_f w_i^2 along
z_B at its position with the drag torque sigma_i c_tau f_i about z_B (MuJoCo site actuators,
so the force/torque mapping runs in C). The thrust applied during step k is c_f wbar_k^2
with wbar_k the exact mean speed over the step, so a command held from t_k acts from t_k.

Limits: the plant clamps commanded speeds to [0, w_max] with c_f w_max^2 = f_max. It does
**not** clamp at f_min: f_min > 0 is an operating limit for controllers (propellers kept
spinning for attitude authority), while a zero command stops the motor and gives zero
thrust, as when the mission switches the motors off on the slope.

Surfaces and air (``[aero]``, :mod:`tetherland.models.aero`): with any effect on, every
physics step multiplies each rotor's thrust (and so its drag torque, both through the
actuator's control) by its surface factor, from the rotor's pose at the start of the
step and the scene's real shapes (:func:`tetherland.sim.aero.scene_shapes`), and applies
the rotor drag (and the wall pull) as a force and torque at the centre of mass through
``qfrc_applied`` of the vehicle's free joint (a compiled kernel). With every effect off,
none of this runs and the plant is the plain c_f w^2 plant.

Time: ``step()`` advances from t_k to t_{k+1}. MuJoCo evaluates sensors before integrating,
so after ``step()`` the sensor readings (IMU, cable force, touch) refer to t_k, while
:meth:`Plant.state` is the state at t_{k+1} = :attr:`Plant.time`.
"""

from __future__ import annotations

import math
from typing import NoReturn

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from tetherland.config import Scenario
from tetherland.errors import SimulationError
from tetherland.geometry import FloatArray, landed_rotation
from tetherland.interfaces import StateEstimate
from tetherland.models.aero import aero_into, aero_work_size
from tetherland.rotations import quat_to_rotmat, rotmat_to_quat
from tetherland.sim import step_kernel as sk
from tetherland.sim.aero import aero_model
from tetherland.sim.cable import Cable, ElasticCable, HangingLine, MagnetCable, make_cable
from tetherland.sim.hook import Hook, HookState
from tetherland.sim.mjcf import (
    CONTACT_PARTNERS,
    FRAME_PARTS,
    SENSOR_SLICES,
    SceneLayout,
    build_mjcf,
)
from tetherland.sim.model_cache import compiled_model
from tetherland.sim.native import address, step_functions
from tetherland.sim.step_kernel import (
    R_BASE,
    R_CMD,
    R_FACTOR,
    R_SPINNING,
    R_W,
    command_rotors,
    physics_step,
    rotor_row_into,
    rotor_state,
    rotor_step,
)
from tetherland.state import LinkState, RigidBodyState, link_state_of

_BAD_STATE_WARNINGS = (
    int(mujoco.mjtWarning.mjWARN_BADQPOS),
    int(mujoco.mjtWarning.mjWARN_BADQVEL),
    int(mujoco.mjtWarning.mjWARN_BADQACC),
)
LINE_SETTLE_TIME = 0.5
"""Time the bar mechanism's line and hook settle at reset, the vehicle held [s]."""
ROTOR_STATE_WIDTH = 15
"""Width of :meth:`Plant.rotor_state_into`'s row: speeds, thrusts, factors, aero force."""
CONTACT_PEAK_WIDTH = 11
"""Width of :meth:`Plant.contact_peaks_into`'s row: the landers' peaks on the surface (4)
and the ground (4), the frame's peak force, the part code and the deepest penetration."""
_N_LANDER_PEAKS = 4 * len(CONTACT_PARTNERS)
# the peaks of a read with no contact since the last: no force, no part (-1), no depth
# (written -0.0, the negated zero minimum of a contact-free read)
_NO_CONTACT_PEAKS = [0.0] * (_N_LANDER_PEAKS + 1) + [-1.0, -0.0]


class Plant:
    """The simulated vehicle, cable and scene of one scenario.

    Parameters
    ----------
    scenario : Scenario
        Vehicle, tether, surface, anchor and ``[sim]`` settings.
    compiled_step : bool
        Step a plant with the elastic cable and the capture disk (every scenario's
        default) in one compiled call per physics step
        (:func:`~tetherland.sim.step_kernel.physics_step`); False: through the Python
        bindings, the same bits (for tests). Other mechanisms always step in Python.

    Attributes
    ----------
    scenario : Scenario
    layout : SceneLayout
        Anchor, surface frame, ground and start pad positions.
    model, data : mujoco.MjModel, mujoco.MjData
        The MuJoCo model (owned: engaging and releasing the cable changes it) and its data.
    hook : Hook
        The hook state machine and its events.
    cable : Cable
        The cable model of ``scenario.tether`` (ideal, elastic or chain, docs/tether.md).
    xml : str
        The generated MJCF.
    """

    def __init__(self, scenario: Scenario, *, compiled_step: bool = True) -> None:
        self.scenario = scenario
        self.layout = SceneLayout.from_scenario(scenario)
        self.xml = build_mjcf(scenario, self.layout)
        # compiled once per distinct MJCF in this process; this plant's own copy
        self.model = compiled_model(self.xml)
        self.data = mujoco.MjData(self.model)
        m = self.model
        self._att_site = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "attachment")
        self.dt = float(m.opt.timestep)
        self.steps_per_second = scenario.sim.steps_per_second
        v = scenario.vehicle
        self._r_att = np.asarray(v.cable_attachment, dtype=float)
        self._c_f = v.thrust_coefficient
        self._w_max = math.sqrt(v.f_max / v.thrust_coefficient)
        tau = v.motor_time_constant
        self._alpha = math.exp(-self.dt / tau) if tau > 0 else 0.0
        # mean of w over a step: w_cmd + (w_k - w_cmd) tau (1 - alpha) / dt
        self._mean_factor = tau * (1.0 - self._alpha) / self.dt if tau > 0 else 0.0
        self._gear0 = self.model.actuator_gear[0:4].copy()  # nominal rotor gears
        self.aero = aero_model(scenario, m)
        """The ``[aero]`` model (None: every effect off)."""
        # the rotor state of the per-step kernel (sim/step_kernel.py): speeds, commands,
        # thrusts before the surface factors, the factors of the last step, the lag's
        # constants and whether the speeds still move toward the command
        self._rot = rotor_state(self._c_f, self._mean_factor, self._alpha, 1e-12 * self._w_max,
                                self.aero is not None)  # fmt: skip
        self._w = self._rot[R_W : R_W + 4]
        self._w_cmd = self._rot[R_CMD : R_CMD + 4]
        self._f_base = self._rot[R_BASE : R_BASE + 4]  # c_f wbar^2 [N]
        self._factors = self._rot[R_FACTOR : R_FACTOR + 4]  # surface factors, last step [-]
        if self.aero is not None:
            a = self.aero
            # the acting thrust may exceed f_max by the factor's bound
            m.actuator_ctrlrange[0:4, 1] *= a.factor_bound
            self._aero_args = (a.rotor_centres_B, a.samples, a.shapes, a.params)
            work = np.empty(aero_work_size(a.shapes.shape[0]))
        else:  # (the kernel does not read them)
            self._aero_args = (np.zeros((0, 3)), np.zeros((0, 2)), np.zeros((0, 16)),
                               np.zeros(0))  # fmt: skip
            work = np.empty(0)
        # Views into MjData (stable for the life of ``data``).
        self._ctrl = self.data.ctrl[0:4]  # rotor thrusts (the elastic cable owns ctrl[4])
        self._wrench = self.data.qfrc_applied[0:6]  # aero force F_W and torque F_B
        self._aero_work = work
        self._step_args = (self._rot, self.data.qpos[0:7], self.data.qvel[0:6],
                           *self._aero_args, work, self._ctrl, self._wrench)  # fmt: skip
        self._p_att_view = self.data.site_xpos[self._att_site]
        self._qpos, self._qvel = self.data.qpos[0:7], self.data.qvel[0:6]
        self._warnings = self.data.warning.number
        self.sensordata = self.data.sensordata
        # the landers' normal forces on the surface and the ground (contact sensors, every
        # third entry: normal, tangent, tangent) and their peaks since the last read
        first = SENSOR_SLICES[f"lander0_{CONTACT_PARTNERS[0]}"].start
        last = SENSOR_SLICES[f"lander3_{CONTACT_PARTNERS[-1]}"].stop
        self._lander_normals = self.sensordata[first:last:3]
        self._lander_peak = np.zeros(self._lander_normals.shape)
        # the number of contacts of the parts but the landers (> 0: a crash), the deepest
        # contact of the vehicle (distance <= 0) and its least since the last read
        self._frame_found = self.sensordata[SENSOR_SLICES["frame_contacts"]]
        self._depth_view = self.sensordata[SENSOR_SLICES["vehicle_depth"]]
        self._depth_min = 0.0
        # the other parts: geom id -> index in FRAME_PARTS, their normal forces at the last
        # step with a part in contact and their peaks since the last read
        self._part_of_geom = {
            mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, name): j
            for j, name in enumerate(FRAME_PARTS)
        }
        self._part_now = np.zeros(len(FRAME_PARTS))
        self._part_peak = np.zeros(len(FRAME_PARTS))
        self._force6 = np.zeros(6)
        geo = self.layout.geometry
        self.cable: Cable = make_cable(m, self.data, scenario, geo.p_A, geo.R_WA[:, 0])
        self._line = self.cable if isinstance(self.cable, HangingLine) else None
        """The bar mechanism's hanging line (None: the capture disk decides engagement)."""
        if self._line is not None:
            self._line.set_anchor(geo.p_A, self.layout.ground_z, geo.R_WA[:, 1])
            self._crown_site = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "hook_crown")
        self._magnet = self.cable if isinstance(self.cable, MagnetCable) else None
        """The magnet mechanism's cable and magnet (None: another mechanism)."""
        if self._magnet is not None:
            self._magnet.set_anchor(geo.p_A, geo.surface.R_WS[:, 2])
            self._crown_site = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "magnet_eye")
        self._contact_hook: HangingLine | MagnetCable | None = self._line or self._magnet
        """The mechanism whose contact decides the catch (None: the capture disk)."""
        self.hook = Hook(
            geo.p_A,
            self.layout.approach_W,
            scenario.tether.capture_radius,
            scenario.tether.hook_drop,
            miss_radius=scenario.tether.length,
        )
        # hook.side(x, y, z) >= 0  <=>  n.(x, y, z) >= c0 (precomputed for the step loop)
        self._hook_plane = self.hook.plane
        self._hook_offset = self.hook.offset_W  # (fixed for the hook's life) [m]
        self._prev_att = (0.0, 0.0, 0.0)
        self._hook_side = False
        self._tick = 0
        self._hook_state: np.ndarray | None = None  # (the compiled step's capture plane)
        self._table = self._address_table() if compiled_step else None
        self.compiled_step = self._table is not None
        """Whether :meth:`step` makes one compiled call per physics step."""
        # what step() reads, in one tuple: the cable's step (mj_step with the cable force,
        # sim/cable.py), the kernel's arguments, the hook, views into MjData and the
        # capture plane (line: the mechanism whose contact decides the hook instead)
        self._step_context = (
            self.cable.advance, self._step_args, self.hook, self._p_att_view, self._warnings,
            _BAD_STATE_WARNINGS[2], self._contact_hook, *self._hook_plane, self.data, self.dt,
        )  # fmt: skip
        # what the compiled step's loop reads (sim/step_kernel.physics_step does the rest)
        self._compiled_context = (self.data, self.hook, self._hook_state, self.dt)
        self.reset()

    def __reduce_ex__(self, protocol: object) -> NoReturn:
        """A plant is neither copied nor pickled: its views and its compiled step's address
        table point into its own MuJoCo data (a copy would step the original's)."""
        raise TypeError(
            "a Plant cannot be copied or pickled (its views and its compiled step point into "
            "its own MuJoCo data): build another one with Plant(scenario)"
        )

    # -- state ----------------------------------------------------------------------------

    @property
    def time(self) -> float:
        """Simulation time t_k = k dt of the current state [s] (integer tick count inside)."""
        return self._tick * self.dt

    @property
    def tick(self) -> int:
        """Number of physics steps since the last reset."""
        return self._tick

    def start_state(self) -> RigidBodyState:
        """At rest on the start pad, level, x_B along x_A (the downhill horizontal)."""
        return self.layout.start_state(self.scenario.vehicle.h_R)

    def landed_state(self) -> RigidBodyState:
        """At rest at the landing point p*_L with z_B = z_S (condition (2)) and x_B at the
        planner's heading psi* from x_S (:func:`tetherland.geometry.landed_rotation`)."""
        geo = self.layout.geometry
        R = landed_rotation(geo.surface.R_WS, math.radians(self.scenario.planner.heading_deg))
        return RigidBodyState.at_rest(geo.p_R_landed, rotmat_to_quat(R))

    def reset(
        self,
        state: RigidBodyState | None = None,
        *,
        rotor_speeds: ArrayLike | None = None,
        cable_engaged: bool = False,
    ) -> None:
        """Restart at t = 0 from ``state`` (default: :meth:`start_state`).

        Parameters
        ----------
        state
            Initial state of the vehicle.
        rotor_speeds : (4,) array, optional
            Initial rotor speeds, also the held command (default: stopped) [rad/s].
        cable_engaged
            Start with the cable hooked to the anchor.
        """
        mujoco.mj_resetData(self.model, self.data)
        self._tick = 0
        self._lander_peak[:] = 0.0
        self._part_peak[:] = 0.0
        self._depth_min = 0.0
        self._touched = False
        self.model.actuator_gear[0:4] = self._gear0
        self._write_state(self.start_state() if state is None else state)
        w0 = np.zeros(4) if rotor_speeds is None else np.asarray(rotor_speeds, dtype=float)
        self.command(w0)
        self._w[:] = self._w_cmd
        self._rot[R_SPINNING] = 1.0
        self._set_cable(cable_engaged)
        self.hook.reset(cable_engaged)
        self.forward()
        if self._line is not None:
            self._settle_line()
        self._track_hook_point()

    def _settle_line(self) -> None:
        """Let the laid-out line and hook come to rest with the vehicle held still
        (:data:`LINE_SETTLE_TIME`), so that the run does not start with the hook falling or
        bouncing (a tension transient the robot would read)."""
        d = self.data
        q0, v0 = d.qpos[0:7].copy(), d.qvel[0:6].copy()
        for _ in range(round(LINE_SETTLE_TIME / self.dt)):
            self.cable.advance()
            d.qpos[0:7], d.qvel[0:6] = q0, v0
        d.time = 0.0
        self.forward()

    @property
    def hook_point_W(self) -> FloatArray:
        """The hook's true position at :attr:`time` [m]: the crown of the bar mechanism's
        hook body, the cable's eye on the magnet, else the capture-disk model's hook
        point."""
        out = np.empty(3)
        self.hook_point_into(out)
        return out

    def hook_point_into(self, out: FloatArray) -> None:
        """Write :attr:`hook_point_W` into ``out[:3]`` [m]."""
        if self._contact_hook is not None:
            out[:3] = self.data.site_xpos[self._crown_site]
        else:
            np.add(self._p_att_view, self._hook_offset, out[:3])

    def set_state(self, state: RigidBodyState) -> None:
        """Overwrite position, attitude and velocities (time and rotors unchanged).

        Kinematics and sensors are recomputed, and the hook starts tracking from the new
        position (teleporting never counts as crossing the capture disk). An engaged
        massive cable is laid out again, at rest, to the new attachment point.
        """
        self._write_state(state)
        self.cable.follow_vehicle()
        self.forward()
        self._track_hook_point()

    def show_pose(self, qpos_vehicle: ArrayLike, engaged: bool) -> None:
        """Put the vehicle at rest at ``qpos_vehicle`` = [p_W (3), q_WB (4)] with the cable
        engaged or not, for drawing a logged pose (replay; time and rotors unchanged).

        A massive cable is laid out at rest from the anchor to the attachment point.
        """
        d = self.data
        d.qpos[0:7] = np.asarray(qpos_vehicle, dtype=float)
        d.qvel[:] = 0.0
        self._set_cable(engaged)
        self.hook.reset(engaged)
        self.forward()

    def _write_state(self, state: RigidBodyState) -> None:
        d = self.data
        d.qpos[0:3] = state.p_W
        q = np.asarray(state.q_WB, dtype=float)
        d.qpos[3:7] = q / np.linalg.norm(q)
        d.qvel[0:3] = state.v_W
        d.qvel[3:6] = state.omega_B

    def state(self) -> RigidBodyState:
        """Ground truth at :attr:`time` (copies)."""
        qpos, qvel = self.data.qpos, self.data.qvel
        return RigidBodyState(
            p_W=qpos[0:3].copy(),
            v_W=qvel[0:3].copy(),
            q_WB=qpos[3:7].copy(),
            omega_B=qvel[3:6].copy(),
        )

    @property
    def qpos(self) -> FloatArray:
        """The vehicle's qpos view: [p_W (3), q_WB (4)] at :attr:`time` (do not write; a
        massive cable's joints follow in ``data.qpos``)."""
        return self._qpos

    @property
    def qvel(self) -> FloatArray:
        """The vehicle's qvel view: [v_W (3), omega_B (3)] at :attr:`time` (do not write)."""
        return self._qvel

    def forward(self) -> None:
        """Recompute kinematics, forces and sensors at the current state (no time step)."""
        if self.aero is None:
            self._ctrl[:] = [self._c_f * w * w for w in self._w.tolist()]
        else:
            self._f_base[:] = [self._c_f * w * w for w in self._w.tolist()]
            self._apply_aero()
        self.cable.forward()

    def _apply_aero(self) -> None:
        """Acting thrusts into the actuators and the aero wrench into the free joint, from
        the state at :attr:`time` and the thrusts ``_f_base``."""
        aero_into(self._qpos, self._qvel, self._f_base, *self._aero_args, self._factors,
                  self._ctrl, self._wrench)  # fmt: skip

    def attachment_point(self) -> FloatArray:
        """Cable attachment point p_R + R_WB r_att at :attr:`time` [m]."""
        qpos = self.data.qpos
        return qpos[0:3] + quat_to_rotmat(qpos[3:7]) @ self._r_att

    def link_state(self) -> LinkState:
        """Link angles and rates of the attachment point around the anchor, at :attr:`time`.

        phi and delta as in docs/theory.md section 3 (F_A), whether the cable is taut or not.
        """
        geo = self.layout.geometry
        x = np.concatenate((self._qpos, self._qvel))
        return link_state_of(x, self._r_att, geo.p_A, geo.R_WA)

    def truth_estimate(self) -> StateEstimate:
        """The ground truth at :attr:`time` as a :class:`StateEstimate` (tension: last step)."""
        return StateEstimate(
            t=self.time, body=self.state(), link=self.link_state(), tension=self.tension
        )

    # -- rotors ---------------------------------------------------------------------------

    def command(self, rotor_speeds: ArrayLike) -> None:
        """Hold new ESC speed commands from now on, clamped to [0, w_max] [rad/s].

        The caller validates (finite, shape 4); this is on the control path.
        """
        speeds = np.asarray(rotor_speeds, dtype=float)
        if speeds.shape != (4,):
            n = len(speeds) if speeds.ndim else 1
            raise SimulationError(f"expected 4 rotor speed commands, got {n}")
        if not command_rotors(self._rot, speeds, self._w_max):  # (sim/step_kernel.py)
            raise SimulationError(
                f"non-finite rotor speed command {speeds.tolist()} at t = {self.time:.4f} s"
            )

    def set_rotor_efficiency(self, efficiency: ArrayLike) -> None:
        """Scale each rotor's thrust and drag torque by ``efficiency`` (4 factors in (0, 1],
        a rotor fault; :meth:`reset` restores 1) [-].

        The factor scales the MuJoCo actuator gear: the speeds, the commands and
        :attr:`rotor_thrusts` stay the model's c_f w^2, the force applied is eff c_f w^2.
        """
        eff = np.asarray(efficiency, dtype=float)
        if eff.shape != (4,) or not np.all((eff > 0.0) & (eff <= 1.0)):
            raise ValueError(f"rotor efficiency must be 4 factors in (0, 1], got {efficiency}")
        self.model.actuator_gear[0:4] = self._gear0 * eff[:, None]

    @property
    def rotor_efficiency(self) -> FloatArray:
        """Current thrust factor of each rotor [-]."""
        return self.model.actuator_gear[0:4, 2] / self._gear0[:, 2]

    @property
    def has_magnet(self) -> bool:
        """True with the magnet mechanism (the robot commands its EPM and its clip's
        latch)."""
        return self._magnet is not None

    def set_magnet(self, on: bool) -> None:
        """The robot's EPM command: on (its holding force on the plate through the contact)
        or off. Ignored without the magnet mechanism."""
        if self._magnet is not None:
            self._magnet.set_epm(on)

    def set_latch(self, open_: bool) -> None:
        """The robot's command to the latch of the clip that holds the magnet on its boom:
        open (the clip lets the magnet go ``mechanism.latch_time`` later, whether the EPM
        holds it on the plate or not) or closed. Ignored without the magnet mechanism."""
        if self._magnet is not None:
            self._magnet.set_latch(open_)

    def snap_cable(self) -> None:
        """The cable breaks now: detached, and the hook can never engage it again."""
        self.hook.sever(self.time, self.attachment_point())
        self._set_cable(False)
        self._track_hook_point()

    @property
    def speed_limit(self) -> float:
        """w_max with c_f w_max^2 = f_max [rad/s]."""
        return self._w_max

    @property
    def commanded_speeds(self) -> FloatArray:
        """Held (clamped) speed commands [rad/s]."""
        return np.array(self._w_cmd)

    @property
    def rotor_speeds(self) -> FloatArray:
        """Rotor speeds w_i at :attr:`time` [rad/s]."""
        return np.array(self._w)

    @property
    def rotor_thrusts(self) -> FloatArray:
        """Acting rotor thrusts at :attr:`time`: c_f w_i^2 times the surface factor [N]."""
        out = np.empty(ROTOR_STATE_WIDTH)
        self.rotor_state_into(out)
        return out[4:8]

    @property
    def surface_factors(self) -> FloatArray:
        """Surface factor T / T_OGE of each rotor at :attr:`time` (1 with ``[aero]`` off) [-]."""
        out = np.empty(ROTOR_STATE_WIDTH)
        self.rotor_state_into(out)
        return out[8:12]

    @property
    def aero_force(self) -> FloatArray:
        """Rotor drag (and wall pull) on the vehicle at :attr:`time`, F_W [N]."""
        out = np.empty(ROTOR_STATE_WIDTH)
        self.rotor_state_into(out)
        return out[12:15]

    def rotor_state_into(self, out: FloatArray) -> None:
        """Write [w (4), thrusts (4), surface factors (4), aero force F_W (3)] at
        :attr:`time` into ``out[:15]`` (:data:`ROTOR_STATE_WIDTH`; no allocation).

        The thrusts are c_f w_i^2 times the factors; factors and aero force are those the
        plant computed last (at the start of the last step, or by :meth:`reset` /
        :meth:`forward`): one physics step old in a running loop (the step loop does not
        evaluate the model twice).
        """
        rotor_row_into(self._rot, self._wrench, out)  # (sim/step_kernel.py)

    # -- cable ----------------------------------------------------------------------------

    @property
    def cable_engaged(self) -> bool:
        return self.hook.engaged

    @property
    def hook_state(self) -> HookState:
        return self.hook.state

    def engage_cable(self) -> None:
        """Attach the cable to the anchor now (bypassing the hook geometry)."""
        self.hook.reset(True)
        self._set_cable(True)
        self._track_hook_point()

    def release_cable(self) -> None:
        """Detach the cable now (bypassing the hook geometry)."""
        self.hook.reset(False)
        self._set_cable(False)
        self._track_hook_point()

    def _track_hook_point(self) -> None:
        """Start tracking the hook point from the attachment site's current position."""
        x, y, z = self._p_att_view.tolist()
        self._prev_att = (x, y, z)
        self._hook_side = self._contact_hook is None and self.hook.side(x, y, z) >= 0.0
        if self._table is not None:
            h = self._hook_state
            h[sk.H_SIDE] = 1.0 if self._hook_side else 0.0
            h[sk.H_PREV : sk.H_PREV + 3] = (x, y, z)

    def _address_table(self) -> np.ndarray | None:
        """The address table of :func:`~tetherland.sim.step_kernel.physics_step`, for a
        plant with the elastic cable and the capture disk (None otherwise, or without the
        MuJoCo library's functions: :func:`~tetherland.sim.native.step_functions`).

        Its arrays stay referenced by this plant (``_held``); the MjData views are stable
        for the life of ``data``. The point-hook plant's arena cannot overflow (a vehicle
        of a few parts over a slope and the ground), so no MuJoCo error can arise inside the
        compiled call."""
        functions = step_functions()
        cable = self.cable
        if functions is None or type(cable) is not ElasticCable or self._contact_hook is not None:
            return None
        d, m = self.data, self.model
        rot, (centres, samples, shapes, params), work = self._rot, self._aero_args, self._aero_work
        held = [np.ascontiguousarray(a, dtype=float) for a in (centres, samples, shapes, params)]
        centres, samples, shapes, params = held
        hook = np.zeros(sk.HOOK_WIDTH)
        hook[sk.H_NX : sk.H_NX + 3] = self._hook_plane[0:3]
        hook[sk.H_C0] = self._hook_plane[3]
        self._hook_state = hook
        self._held = (*held, hook)
        table = np.zeros(sk.TABLE_SIZE, dtype=np.int64)
        table[sk.T_MODEL], table[sk.T_DATA] = m._address, d._address
        table[sk.T_STEP1], table[sk.T_STEP2] = functions
        table[sk.T_QPOS], table[sk.T_QVEL] = address(self._qpos), address(self._qvel)
        table[sk.T_CTRL], table[sk.T_WRENCH] = address(self._ctrl), address(self._wrench)
        table[sk.T_TENDON_LENGTH] = address(cable._len)
        table[sk.T_TENDON_RATE] = address(cable._vel)
        table[sk.T_CABLE_CTRL], table[sk.T_CABLE] = address(cable._ctrl), address(cable.state)
        table[sk.T_ATTACHMENT] = address(self._p_att_view)
        bad = _BAD_STATE_WARNINGS[2]
        table[sk.T_BAD_QACC] = address(self._warnings[bad : bad + 1], np.int32)
        table[sk.T_HOOK] = address(hook)
        table[sk.T_ROT] = address(rot)
        table[sk.T_CENTRES], table[sk.T_N_CENTRES] = address(centres), centres.shape[0]
        table[sk.T_SAMPLES], table[sk.T_N_SAMPLES] = address(samples), samples.shape[0]
        table[sk.T_SHAPES], table[sk.T_N_SHAPES] = address(shapes), shapes.shape[0]
        table[sk.T_SHAPE_WIDTH] = shapes.shape[1]
        table[sk.T_PARAMS], table[sk.T_N_PARAMS] = address(params), params.size
        table[sk.T_WORK], table[sk.T_N_WORK] = address(work), work.size
        return table

    def _set_cable(self, engaged: bool) -> None:
        # Disengaged, the cable exerts no force and is not drawn (sim/cable.py).
        self.cable.set_engaged(engaged)

    @property
    def tension(self) -> float:
        """Cable tension f_L at the attachment point at the start of the last step [N]."""
        return float(self.sensordata[SENSOR_SLICES["cable_force"]][0])

    @property
    def cable_length(self) -> float:
        """Distance anchor-attachment at the start of the last step [m]."""
        return float(self.sensordata[SENSOR_SLICES["cable_length"]][0])

    @property
    def lander_forces(self) -> FloatArray:
        """Normal contact force on each lander at the start of the last step [N]."""
        return self.sensordata[
            SENSOR_SLICES["lander0_touch"].start : SENSOR_SLICES["lander3_touch"].stop
        ].copy()

    def contact_peaks_into(self, out: FloatArray) -> None:
        """Write the contact peaks over the physics steps since the last call (or the
        reset) into ``out[:11]`` (:data:`CONTACT_PEAK_WIDTH`), and start over:

        - ``out[0:4]``, ``out[4:8]``: the largest normal force of each lander on the
          landing surface, then on the ground [N];
        - ``out[8]``: the largest normal force on any other part of the vehicle
          (:data:`~tetherland.sim.mjcf.FRAME_PARTS`: a crash; a part's force is the sum
          over its contacts) [N];
        - ``out[9]``: the index in ``FRAME_PARTS`` of the part that force acted on (-1 when
          no part touched);
        - ``out[10]``: the deepest penetration of any vehicle geom into anything, >= 0 [m].

        The landers' contact sensors filter by partner geom (:mod:`tetherland.sim.mjcf`);
        a step at which another part has a contact (the sensor ``frame_contacts``) sums
        each part's normal forces from MuJoCo's contact list. The peaks are taken at every
        physics step: a touch that lasts a single step is seen (the judge's touchdowns,
        bounces and crashes).
        """
        if not self._touched:  # no contact since the last read: the peaks are all zero
            out[:CONTACT_PEAK_WIDTH] = _NO_CONTACT_PEAKS
            return
        self._touched = False
        n = _N_LANDER_PEAKS
        out[:n] = self._lander_peak
        parts = self._part_peak
        k = int(parts.argmax())
        force = float(parts[k])
        out[n] = force
        out[n + 1] = k if force > 0.0 else -1
        out[n + 2] = -self._depth_min
        self._lander_peak[:] = 0.0
        parts[:] = 0.0
        self._depth_min = 0.0

    def _part_forces_into(self, out: FloatArray) -> None:
        """Sum the normal force of every contact of each part of
        :data:`~tetherland.sim.mjcf.FRAME_PARTS` at the start of the last step into
        ``out`` (MuJoCo's contact list and ``mj_contactForce``) [N]."""
        out[:] = 0.0
        m, d, f6, part_of = self.model, self.data, self._force6, self._part_of_geom
        ncon = d.ncon
        if not ncon:
            return
        geoms = d.contact.geom[:ncon]
        for i in range(ncon):
            g1, g2 = geoms[i]
            j = part_of.get(int(g1), part_of.get(int(g2)))
            if j is not None:
                mujoco.mj_contactForce(m, d, i, f6)
                out[j] += f6[0]

    def _track_parts(self) -> None:
        """A step with a contact of a part but the landers: the parts' peaks."""
        self._part_forces_into(self._part_now)
        np.maximum(self._part_peak, self._part_now, out=self._part_peak)

    @property
    def part_forces(self) -> FloatArray:
        """Normal force on each part of :data:`~tetherland.sim.mjcf.FRAME_PARTS` (summed
        over its contacts) at the start of the last step [N]."""
        out = np.zeros(len(FRAME_PARTS))
        self._part_forces_into(out)
        return out

    @property
    def frame_contact_force(self) -> float:
        """Largest normal force on any part but the landers (hub, mount, arms, legs, rotor
        guards; a crash when > 0) at the start of the last step [N]."""
        return float(self.part_forces.max())

    @property
    def frame_contact_peak(self) -> float:
        """Largest normal force on any part but the landers over the physics steps since
        the last :meth:`contact_peaks_into` (or the reset), without starting over [N]."""
        return float(self._part_peak.max())

    @property
    def penetration(self) -> float:
        """Depth of the deepest contact of any vehicle geom at the start of the last step,
        >= 0 (MuJoCo's contact distance) [m]."""
        return -float(self._depth_view[0])

    # -- stepping -------------------------------------------------------------------------

    def step(self, n: int = 1) -> None:
        """Advance ``n`` physics steps with the held command.

        Raises
        ------
        SimulationError
            If MuJoCo reports a non-finite or diverging state.
        """
        table = self._table
        if table is not None:
            data, hook, h, dt = self._compiled_context
            for _ in range(n):
                found = physics_step(table)
                if data.ncon:  # (no contact: every contact sensor reads 0, nothing to track)
                    self._track_contacts()
                k = self._tick
                self._tick = k + 1
                if found:
                    if found == sk.STEP_DIVERGED:
                        self._diverged(k * dt)
                    prev = h[sk.H_PREV : sk.H_PREV + 3].tolist()
                    now = h[sk.H_NOW : sk.H_NOW + 3].tolist()
                    h[sk.H_PREV : sk.H_PREV + 3] = now
                    self._hook_side = h[sk.H_SIDE] != 0.0
                    if hook.cross(k * dt, tuple(prev), tuple(now)) is not None:
                        self._set_cable(hook.engaged)
            return
        # (one tuple, built once: this runs once per physics step)
        (advance, args, hook, p_att, warn, bad_qacc, line, nx, ny, nz, n_dot_p0, data,
         dt) = self._step_context  # fmt: skip
        for _ in range(n):
            rotor_step(*args)
            advance()
            if data.ncon:  # (no contact: every contact sensor reads 0, nothing to track)
                self._track_contacts()
            k = self._tick
            self._tick = k + 1
            # Kinematics in ``data`` refer to t_k after mj_step; a hook crossing found
            # now takes effect from the next step.
            x, y, z = p_att.tolist()
            if x != x or warn[bad_qacc]:  # NaN state or MuJoCo's bad-acceleration flag
                self._diverged(k * dt)
            if line is not None:  # no capture plane: the contact decides (line or magnet)
                if line.changed:
                    hook.record(k * dt, line.caught, data.site_xpos[self._crown_site])
                continue
            side = nx * x + ny * y + nz * z >= n_dot_p0
            if side != self._hook_side:
                self._hook_side = side
                if hook.cross(k * dt, self._prev_att, (x, y, z)) is not None:
                    self._set_cable(hook.engaged)
            self._prev_att = (x, y, z)

    def _track_contacts(self) -> None:
        """After a step with contacts: the landers' peak forces, the parts in contact (a
        crash) and the deepest penetration since the last read."""
        self._touched = True
        np.maximum(self._lander_peak, self._lander_normals, out=self._lander_peak)
        if self._frame_found[0]:  # a part but the landers touches: a crash
            self._track_parts()
        depth = self._depth_view[0]
        if depth < self._depth_min:
            self._depth_min = float(depth)

    def _diverged(self, t: float) -> None:
        names = ("qpos", "qvel", "qacc")
        bad = [n for n, i in zip(names, _BAD_STATE_WARNINGS, strict=True) if self._warnings[i]]
        what = f"MuJoCo flagged a bad {', '.join(bad)}" if bad else "non-finite state"
        raise SimulationError(
            f"simulation diverged at t = {t:.4f} s ({what}); "
            "check the commands and the [sim] time step and constraint time constants"
        )
