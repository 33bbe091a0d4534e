"""The stages of one decision of one formation, compiled: :func:`formation_env.sim.step.decide_chunk`
is the chain of them (its module docstring gives the order and the physics).

Per physics substep: :func:`demands` (guidance) -> :func:`ambient_wind` -> :func:`control` -> the physics step
(:mod:`.physics`: ELL, coupling, RK4, envelope, a chunk of formations at once) -> :func:`advance_turbulence` ->
:func:`integrate_reference` -> :func:`step_separation_check`; after the substeps the outputs:
:func:`slot_frame_angle`, :func:`crash_and_slot_error`, :func:`nearest_separations`,
:func:`episode_flags`, :func:`formation_saving`, :func:`reward_output`, :func:`observe_one`.

Every stage works on formation ``b`` of the state ``s`` (:class:`~formation_env.sim.state.SimState`)
with the parameters ``p`` (:class:`~formation_env.sim.params.StepParams`), or only the part of them it
needs; what one decision needs as scratch is one :class:`DecisionScratch`, allocated once per decision
(allocating inside the substep loop costs ~10 % of a step). In the decision, ``p``, ``s``, the output and
the scratch are :class:`~formation_env.sim.views.StructView` s of those named tuples (fields read the same):
a stage binding a named tuple of arrays takes and releases a reference count per array, a view one. Shapes: V
vehicles; units SI; frames NED earth, body x forward / y starboard / z down, track frame (x along the track, y
starboard, z down).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba as nb
import numpy as np

from ..aircraft.kernels import air_data_kernel
from ..aircraft.state import POS_D, POS_E, POS_N, QUAT
from ..atmosphere.frozen_field import N_STREAMS_PER_LANE, advance_field_one, sample_field_one
from ..atmosphere.spectral_field_kernels import sample_modes_one
from ..control.law import N_CSTATE, fcs_update
from ..frames import quaternion_dcm_terms, track_to_ned_xy
from ..wake.arrays import evaluate_formation
from ..wake.benefit import AIR_DENSITY_SL, induced_drag_saving_one, saving_from_drags
from .guidance import formation_demands, gust_wind_ned, leader_wind, reference_path, schedule_features
from .kernels import ell_inputs, min_separation_each, position_finite, separation_each_known, step_separation
from .observe import box_depth_each, observe_formation, reward_formation, slot_error
from .params import RESIDUAL, SETPOINTS, SURFACES, TURBULENCE_LANES, TURBULENCE_OFF, TURBULENCE_SPECTRAL
from .views import struct_view

__all__ = ["FieldScratch", "DecisionScratch", "field_scratch", "decision_scratch", "ground_velocity_ned", "demands",
           "sample_turbulence", "ambient_wind", "setpoint_shift", "control", "advance_turbulence", "integrate_reference", "record_finite_positions", "step_separation_check",
           "decision_over", "slot_frame_angle", "crash_and_slot_error", "nearest_separations", "episode_flags",
           "formation_benefit", "formation_saving", "reward_output", "observe_one"]

_jit = nb.njit(cache=True, error_model="numpy")
# The stages called at every physics step are inlined into the decision at numba IR level, and so are the
# stages called once a decision that only call further kernels (formation_saving, formation_benefit,
# observe_one): each compiled function links and re-optimises everything it calls (numba), so a function of its
# own above the ELL solve is that solve compiled once more.
_jit_inline = nb.njit(cache=True, error_model="numpy", inline="always")
QUAT0 = QUAT.start  # the attitude quaternion's first column (numba slices by integer constants)
# A compiled call given a named tuple increfs and decrefs every array in it (StepParams holds ~70, SimState
# ~40): a stage called with the named tuples themselves (outside the decision) takes the smallest part it needs.


class FieldScratch(NamedTuple):
    """Scratch of one turbulence filter step and read of a formation (V aircraft)."""

    normals: np.ndarray  # (N_STREAMS_PER_LANE,) the lane normals of one filter step
    along: np.ndarray  # (V,) along-track coordinates, m
    cross: np.ndarray  # (V,) cross-track coordinates, m
    down: np.ndarray  # (V,) down coordinates, m
    slot0: np.ndarray  # (V,) int64 ring slots read
    slot1: np.ndarray  # (V,) int64
    frac: np.ndarray  # (V,) interpolation fractions
    corr: np.ndarray  # (V, V) correlation matrix
    lo: np.ndarray  # (V, V) its Cholesky factor
    gust: np.ndarray  # (V, 3) gusts in the track frame, m/s


class DecisionScratch(NamedTuple):
    """The per-decision working arrays of one formation (V vehicles)."""

    ambient: np.ndarray  # (V, 3) ambient wind at each UAV, m/s NED
    velocity: np.ndarray  # (V, 3) ground velocity at the start of the physics step, m/s NED
    command: np.ndarray  # (V, 4) controls of the physics step
    new_state: np.ndarray  # (V, 16) state after the physics step
    pre_state: np.ndarray  # (V, 16) state before the physics step (its collision check)
    status: np.ndarray  # (V,) int64 envelope status of the physics step
    status_any: np.ndarray  # (V,) int64 envelope status bits of the decision so far
    gust3: np.ndarray  # (3,) the scenario's gust
    zero_turb: np.ndarray  # (V, 3) zeros: the body-axis turbulence input (turbulence is in the ambient wind)
    wind12: np.ndarray  # (12,) the control's air-data wind vector (zeros but ambient and induced wind)
    pd3: np.ndarray  # (3,) one UAV's position demand, m NED (also the reference path's)
    vd3: np.ndarray  # (3,) one UAV's velocity demand, m/s NED
    rate: np.ndarray  # (N_CSTATE,) controller state rates
    signals: np.ndarray  # (10,) controller signals
    ell_pos: np.ndarray  # (V, 3) ELL poses of the last substep's solve (the formation benefit's)
    ell_euler: np.ndarray  # (V, 3)
    ell_speed: np.ndarray  # (V,)
    ell_alpha: np.ndarray  # (V,)
    ell_beta: np.ndarray  # (V,)
    last_pos: np.ndarray  # (V, 3) last finite CG position of each UAV, m NED
    known: np.ndarray  # (V,) bool: a finite position of the UAV was seen
    aic_keep: np.ndarray  # (N, N + 1) the last substep's AIC and right-hand side before elimination (benefit on), else (0, 0)
    no_keep: np.ndarray  # (0, 0): the other substeps keep nothing
    field: FieldScratch


@_jit
def field_scratch(nv):
    """A :class:`FieldScratch` for V = nv aircraft."""
    return FieldScratch(normals=np.empty(N_STREAMS_PER_LANE), along=np.empty(nv), cross=np.empty(nv),
                        down=np.empty(nv), slot0=np.empty(nv, dtype=np.int64), slot1=np.empty(nv, dtype=np.int64),
                        frac=np.empty(nv), corr=np.empty((nv, nv)), lo=np.empty((nv, nv)), gust=np.empty((nv, 3)))


@_jit
def decision_scratch(s, b, benefit_on=False):
    """A :class:`DecisionScratch` for formation b, with the finite positions of its current state
    recorded (:func:`record_finite_positions`); with ``benefit_on`` room to keep the last substep's AIC."""
    nv = s.aircraft.shape[1]
    n_keep = s.circulation.shape[1] if benefit_on else 0
    sc = DecisionScratch(
        ambient=np.empty((nv, 3)), velocity=np.empty((nv, 3)), command=np.empty((nv, 4)),
        new_state=np.empty((nv, s.aircraft.shape[2])), pre_state=np.empty((nv, s.aircraft.shape[2])),
        status=np.zeros(nv, dtype=np.int64), status_any=np.zeros(nv, dtype=np.int64), gust3=np.empty(3),
        zero_turb=np.zeros((nv, 3)), wind12=np.zeros(12), pd3=np.empty(3), vd3=np.empty(3), rate=np.empty(N_CSTATE), signals=np.empty(10), ell_pos=np.empty((nv, 3)),
        ell_euler=np.empty((nv, 3)), ell_speed=np.empty(nv), ell_alpha=np.empty(nv), ell_beta=np.empty(nv),
        last_pos=np.empty((nv, 3)), known=np.zeros(nv, dtype=np.bool_),
        aic_keep=np.empty((n_keep, n_keep + 1)), no_keep=np.empty((0, 0)), field=field_scratch(nv))
    record_finite_positions(s, b, sc)
    return struct_view(sc)


@_jit
def ground_velocity_ned(x, out):
    """Ground velocity (V, 3) m/s NED of the states x (V, 16): the body velocity rotated to NED."""
    for a in range(x.shape[0]):
        xa = x[a]
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = quaternion_dcm_terms(xa[6], xa[7], xa[8], xa[9])
        out[a, 0] = r00 * xa[0] + r01 * xa[1] + r02 * xa[2]
        out[a, 1] = r10 * xa[0] + r11 * xa[1] + r12 * xa[2]
        out[a, 2] = r20 * xa[0] + r21 * xa[1] + r22 * xa[2]


@_jit_inline
def demands(scenario, s, b, t, vel):
    """Guidance at time t (s): the ground velocities ``vel`` (V, 3) of formation b's UAVs, then vehicle
    0's reference path and the followers' slot demands into ``s.position_demand[b]`` /
    ``s.velocity_demand[b]`` (:func:`formation_env.sim.guidance.formation_demands`); ``scenario`` the
    :class:`~formation_env.sim.params.ScenarioArrays`."""
    ground_velocity_ned(s.aircraft[b], vel)
    formation_demands(scenario, t, s.aircraft[b], vel, s.reference_position[b], s.manoeuvre[b], s.slot_jitter[b],
                      s.position_demand[b], s.velocity_demand[b])
    if scenario.leader_air_relative:
        # an air-relative leader: its reference is carried along the track and vertically by the air it flies in
        # (the wind at it now, and the distance that wind has carried it, s.reference_position[b, 0 and 2]); the
        # followers' slots hang off vehicle 0's actual position and track direction, which this leaves as they were
        for k in (0, 2):
            s.position_demand[b, 0, k] += s.reference_position[b, k]
            s.velocity_demand[b, 0, k] += leader_wind(scenario, s.steady_wind[b], s.gust_ned[b, 0], t, k)


@_jit
def sample_turbulence(turbulence, field, s, b, fs, t):
    """Turbulence of formation b at time t (s; the UAVs' current positions are there then), into
    ``s.gust_ned[b]`` (V, 3) m/s NED and ``s.gust_omega_body[b]`` (V, 3) rad/s body. ``turbulence``:
    ``TURBULENCE_SPECTRAL`` the spectral field (:mod:`formation_env.atmosphere.spectral_field`) at each UAV's CG,
    frozen in the air moving with the steady wind, with its rotational gusts over the span and to the tail;
    ``TURBULENCE_LANES`` the lanes (cross-correlated, transport-delayed); ``TURBULENCE_INDEPENDENT`` independent
    lanes (each UAV its own stream, no delay); the lanes have no rotational gusts (zero). Non-finite values (a
    diverged UAV, episode ending) read as 0.
    ``field`` the :class:`~formation_env.sim.params.TurbulenceParams`, fs a :class:`FieldScratch`."""
    nv = s.gust_ned.shape[1]
    chi = math.atan2(s.velocity_demand[b, 0, 1], s.velocity_demand[b, 0, 0])
    if not math.isfinite(chi):
        chi = 0.0
    if turbulence == TURBULENCE_SPECTRAL:
        x = s.aircraft[b]
        sample_modes_one(field.modes, s.modes, b, x[:, POS_N:POS_D + 1], x[:, QUAT0:QUAT0 + 4], t, s.steady_wind[b], chi,
                         s.gust_ned[b], s.gust_omega_body[b])
        return
    if turbulence == TURBULENCE_LANES:
        pos = s.aircraft[:, :, POS_N:POS_D + 1]
        sample_field_one(field.lanes, s.field, b, pos, chi, s.gust_ned, fs.along, fs.cross, fs.down, fs.slot0,
                         fs.slot1, fs.frac, fs.corr, fs.lo, fs.gust)
    else:
        head = s.field.head[b]
        cs, sn = math.cos(chi), math.sin(chi)
        sig = field.lanes.sigma_mps
        for i in range(nv):
            u = sig[0] * s.field.ring[b, head, 0, i]
            v = sig[1] * s.field.ring[b, head, 1, i]
            s.gust_ned[b, i, 0], s.gust_ned[b, i, 1] = track_to_ned_xy(cs, sn, u, v)
            s.gust_ned[b, i, 2] = sig[2] * s.field.ring[b, head, 2, i]
    for i in range(nv):
        for k in range(3):
            s.gust_omega_body[b, i, k] = 0.0
            if not math.isfinite(s.gust_ned[b, i, k]):
                s.gust_ned[b, i, k] = 0.0


@_jit_inline
def ambient_wind(scenario, s, b, t, out, g):
    """Ambient wind (V, 3) NED m/s at time t: the ``scenario``'s gusts + steady wind + turbulence at
    each UAV (g: (3,) scratch)."""
    gust_wind_ned(scenario, t, g)
    for a in range(out.shape[0]):
        for k in range(3):
            out[a, k] = g[k] + s.steady_wind[b, k] + s.gust_ned[b, a, k]


@_jit
def setpoint_shift(a, low, high):
    """Set-point offset (m) of one axis for action a in [-1, 1]: a * high above 0, -a * low below."""
    return a * high if a >= 0.0 else -a * low


@_jit_inline
def control(p, s, b, actions, sc):
    """Commands (V, 4) of formation b into ``sc.command``: the thesis PID (with set-point-shifted
    demands) for every UAV it flies, the agents' ``actions`` (V, 4) mapped per mode: ``setpoints``
    moves the PID's demands, ``residual`` adds to its command, ``surfaces`` replaces it. Reads
    ``sc.ambient`` and ``sc.velocity``."""
    ap = p.action
    cmd, pd, vd, wind, amb, vel, rate, sig = sc.command, sc.pd3, sc.vd3, sc.wind12, sc.ambient, sc.velocity, sc.rate, \
        sc.signals
    for a in range(cmd.shape[0]):
        agent = ap.agent_mask[a]
        if agent and ap.mode == SURFACES:
            for k in range(4):
                cmd[a, k] = min(max(ap.trim_controls[k] + actions[a, k] * ap.surface_scale[k], ap.command_min[k]),
                                ap.command_max[k])
            continue
        x = s.aircraft[b, a]
        for k in range(3):
            pd[k] = s.position_demand[b, a, k]
            vd[k] = s.velocity_demand[b, a, k]
        if agent and ap.mode == SETPOINTS:
            # shift the demands in the slot frame (along the demanded track, starboard, down)
            # (piecewise linear per axis: 0 is the slot, +-1 the set-point range's ends)
            chi = math.atan2(vd[1], vd[0])
            c, sn = math.cos(chi), math.sin(chi)
            dx, dy, dz = (setpoint_shift(actions[a, 0], ap.setpoint_low_m[0], ap.setpoint_high_m[0]),
                          setpoint_shift(actions[a, 1], ap.setpoint_low_m[1], ap.setpoint_high_m[1]),
                          setpoint_shift(actions[a, 2], ap.setpoint_low_m[2], ap.setpoint_high_m[2]))
            dn, de = track_to_ned_xy(c, sn, dx, dy)
            pd[0] += dn
            pd[1] += de
            pd[2] += dz
            speed = math.sqrt(vd[0] * vd[0] + vd[1] * vd[1] + vd[2] * vd[2])
            f = actions[a, 3] * ap.setpoint_speed_mps / max(speed, 1e-9)
            for k in range(3):
                vd[k] += vd[k] * f
        for k in range(3):
            wind[k] = amb[a, k]
            wind[6 + k] = s.induced_wind_ned[b, a, k]
        airspeed = air_data_kernel(x, wind, p.aircraft.scalars)[0]
        e0, ex, ey, ez = x[6], x[7], x[8], x[9]
        n2 = e0 * e0 + ex * ex + ey * ey + ez * ez
        phi = math.atan2(2.0 * (e0 * ex + ey * ez), e0 * e0 - ex * ex - ey * ey + ez * ez)
        theta = math.asin(min(1.0, max(-1.0, 2.0 * (e0 * ey - ex * ez) / n2)))
        psi = math.atan2(2.0 * (ex * ey + e0 * ez), e0 * e0 + ex * ex - ey * ey - ez * ez)
        fcs_update(x[POS_N:POS_D + 1], vel[a], phi, theta, psi, x[4], x[5], airspeed, pd, vd, s.controller[b, a], p.fcs,
                   cmd[a], rate, sig)
        if agent and ap.mode == RESIDUAL:
            for k in range(4):
                cmd[a, k] = min(max(cmd[a, k] + actions[a, k] * ap.residual_scale[k], ap.command_min[k]),
                                ap.command_max[k])


@_jit_inline
def advance_turbulence(turbulence, field, s, b, fs):
    """The turbulence of formation b one step forward and sampled at the new positions (called after
    the physics step, before the step counter moves on: the new positions are at (step + 1) dt); the
    lanes advance their filters, the spectral field is frozen and only moves with the air. Nothing when
    ``turbulence`` is ``TURBULENCE_OFF``. fs: a :class:`FieldScratch`."""
    if turbulence != TURBULENCE_OFF:
        if turbulence != TURBULENCE_SPECTRAL:
            advance_field_one(field.lanes, s.field, b, fs.normals)
        sample_turbulence(turbulence, field, s, b, fs, (s.step[b] + 1) * field.modes.dt_s)


@_jit_inline
def integrate_reference(scenario, dt_s, s, b, t, pd, vd):
    """The manoeuvring reference path of formation b integrated one step dt_s from time t (on the
    physics grid), or an air-relative leader's along-track and vertical air displacement (with the wind at the state of
    t + dt_s, which the turbulence was just advanced to); nothing otherwise. pd, vd (3,): scratch."""
    if scenario.manoeuvres:
        reference_path(scenario, t, s.reference_position[b], s.manoeuvre[b], pd, vd)
        for k in range(3):
            s.reference_position[b, k] += dt_s * vd[k]
    elif scenario.leader_air_relative:  # the distance the air has carried the leader's reference, north and down
        for k in (0, 2):
            s.reference_position[b, k] += dt_s * leader_wind(scenario, s.steady_wind[b], s.gust_ned[b, 0], t + dt_s, k)


@_jit
def record_finite_positions(s, b, sc):
    """``sc.last_pos`` / ``sc.known``: the CG position of each UAV of formation b that is finite now
    (what the outputs measure a diverged UAV by)."""
    known, last_pos = sc.known, sc.last_pos
    for a in range(known.shape[0]):
        if position_finite(s.aircraft[b], a):
            known[a] = True
            for k in range(3):
                last_pos[a, k] = s.aircraft[b, a, POS_N + k]


@_jit_inline
def step_separation_check(dt_s, s, b, sc):
    """Smallest CG separation (m) of formation b over the physics step just flown, never NaN: a step
    that overlaps two UAVs is a collision even if it also diverged one of them
    (:func:`formation_env.sim.kernels.step_separation`); then the finite positions are recorded."""
    d = step_separation(sc.pre_state, sc.velocity, s.aircraft[b], dt_s)
    record_finite_positions(s, b, sc)
    return d


@_jit_inline
def decision_over(collision_separation_m, status_any, d):
    """Whether the formation's episode ended in the physics step: a UAV left the envelope
    (``status_any`` (V,) bits), or the step's separation d is below the collision separation (or NaN)."""
    stop = False
    for a in range(status_any.shape[0]):
        if status_any[a] != 0:
            stop = True
    return stop or d < collision_separation_m or d != d


@_jit
def slot_frame_angle(scenario, s, b, vel):
    """Track angle (rad) of the slot frame (the safe box and the slot error's axes): vehicle 0's
    demanded track, or its measured one (vel (V, 3) m/s NED); 0 if not finite."""
    if scenario.slot_along_leader_demand:
        chi_slot = math.atan2(s.velocity_demand[b, 0, 1], s.velocity_demand[b, 0, 0])
    else:
        chi_slot = math.atan2(vel[0, 1], vel[0, 0])
    if not math.isfinite(chi_slot):
        chi_slot = 0.0
    return chi_slot


@_jit
def crash_and_slot_error(axes, s, b, chi_slot, sc, o):
    """``o.crashed[b]`` and ``o.slot_error_m[b]`` (the slot-frame components weighted by ``axes`` (3,); a
    UAV whose state went non-finite is measured at its last finite position; never NaN); returns
    whether any UAV crashed."""
    crashed_any = False
    status_any, known, last_pos = sc.status_any, sc.known, sc.last_pos
    for a in range(known.shape[0]):
        o.crashed[b, a] = status_any[a] != 0
        crashed_any = crashed_any or status_any[a] != 0
        px, py, pz = s.aircraft[b, a, POS_N], s.aircraft[b, a, POS_E], s.aircraft[b, a, POS_D]
        if not position_finite(s.aircraft[b], a) and known[a]:
            px, py, pz = last_pos[a, 0], last_pos[a, 1], last_pos[a, 2]
        dx = px - s.position_demand[b, a, 0]
        dy = py - s.position_demand[b, a, 1]
        dz = pz - s.position_demand[b, a, 2]
        err = slot_error(dx, dy, dz, chi_slot, axes)
        if not math.isfinite(err):  # no finite position or demand known: the previous error, else 0
            err = s.previous_error[b, a] if math.isfinite(s.previous_error[b, a]) else 0.0
        o.slot_error_m[b, a] = err
    return crashed_any


@_jit
def nearest_separations(x, last_pos, known, out):
    """``out`` (V,): each UAV's distance to its nearest neighbour now (states x (V, 16)), at the last
    finite positions ``last_pos`` (V, 3) (``known``) when a position is non-finite (never NaN)."""
    min_separation_each(x, out)
    finite_sep = True
    for a in range(out.shape[0]):
        if out[a] != out[a]:
            finite_sep = False
    if not finite_sep:
        separation_each_known(last_pos, known, out)


@_jit
def episode_flags(collision_separation_m, episode_steps, s, b, min_sep, crashed_any, o):
    """``o.collided``, ``o.min_separation_m`` (inf for one UAV or nothing known; never NaN),
    ``o.terminated``, ``o.truncated`` (``episode_steps`` flown) of formation b; returns whether it
    collided."""
    collided = min_sep < collision_separation_m
    o.collided[b] = collided
    o.min_separation_m[b] = min_sep
    o.terminated[b] = collided or crashed_any
    o.truncated[b] = (not o.terminated[b]) and s.step[b] >= episode_steps
    return collided


@_jit_inline
def formation_benefit(p, s, b, amb, out_saving):
    """Induced-drag saving (V,) of formation b at its current state: one ELL solve at the current
    poses (relative to the ambient air), then Kutta-Joukowski drag against each UAV flying alone
    (:func:`formation_env.wake.benefit.induced_drag_saving_one`). Zero for a formation with a
    non-finite UAV (its episode is ending)."""
    nv = s.aircraft.shape[1]
    for a in range(nv):
        out_saving[a] = 0.0
        for k in range(s.aircraft.shape[2]):
            if not math.isfinite(s.aircraft[b, a, k]):
                return
    w = p.wake
    pos, euler = np.empty((nv, 3)), np.empty((nv, 3))
    speed, alpha, beta = np.empty(nv), np.empty(nv), np.empty(nv)
    ell_inputs(s.aircraft[b], amb, w.wing_origin_body, pos, euler, speed, alpha, beta)
    gamma = np.empty(w.n_panels)
    # nothing kept (an empty keep, as None, but of the type formation_saving passes: one compiled ELL, not two)
    no_keep = np.empty((0, 0))
    evaluate_formation(w, pos, euler, speed, alpha, beta, gamma, np.empty((gamma.shape[0], 3)), np.empty((nv, 3)),
                       np.empty((nv, 3)), np.empty((nv, 3)), np.empty((nv, 3)), no_keep)
    induced_drag_saving_one(w, p.wake_alone, pos, euler, speed, alpha, beta, gamma, out_saving, AIR_DENSITY_SL, no_keep)


@_jit_inline
def formation_saving(p, s, b, crashed_any, solved_last, chunk_drags, d_form, d_alone, sc, o):
    """``o.saving[b]`` with the benefit on: 0 after a crash, read off the last substep's ELL solve
    (its poses and circulation) when there was one, else a fresh solve (:func:`formation_benefit`).
    ``chunk_drags``: that solve's induced drags ``d_form`` and ``d_alone`` (V,) are already taken across the lanes
    of its chunk (:func:`formation_env.sim.physics.drags_chunk`, the same bits)."""
    if p.benefit_on:
        if crashed_any:
            for a in range(sc.known.shape[0]):
                o.saving[b, a] = 0.0
        elif solved_last and chunk_drags:
            saving_from_drags(p.wake, sc.ell_pos, sc.ell_euler, d_form, d_alone, o.saving[b])
        elif solved_last:
            # the isolated circulations from the diagonal blocks of that solve's AIC (kept by solve_chunk)
            induced_drag_saving_one(p.wake, p.wake_alone, sc.ell_pos, sc.ell_euler, sc.ell_speed, sc.ell_alpha,
                                    sc.ell_beta, s.circulation[b], o.saving[b], AIR_DENSITY_SL, sc.aic_keep)
        else:
            ambient_wind(p.scenario, s, b, s.step[b] * p.dt_s, sc.ambient, sc.gust3)
            formation_benefit(p, s, b, sc.ambient, o.saving[b])


@_jit
def reward_output(w, remaining, s, b, actions, chi_slot, collided, o):
    """``o.box_depth_m[b]``, ``o.reward_terms[b]`` and ``o.reward[b]`` of the decision with ``actions``
    (V, 4) (``w`` the :class:`~formation_env.sim.params.RewardParams`, ``remaining`` decisions to the
    time limit); the episode return, previous error and previous action of formation b updated."""
    nv = actions.shape[0]
    box_depth_each(s.aircraft[b], chi_slot, w.box_low_m, w.box_high_m, o.box_depth_m[b])
    reward_formation(w, o.slot_error_m[b], s.previous_error[b], actions, s.previous_action[b], o.saving[b],
                     o.separation_m[b], collided, o.crashed[b], remaining, o.box_depth_m[b], o.reward_terms[b])
    for a in range(nv):
        total = 0.0
        for k in range(o.reward_terms.shape[2]):
            total += o.reward_terms[b, a, k]
        o.reward[b, a] = total
        s.episode_return[b, a] += total
        s.previous_error[b, a] = o.slot_error_m[b, a]
        for k in range(4):
            s.previous_action[b, a, k] = actions[a, k]


@_jit_inline
def observe_one(p, s, b, out_obs):
    """Observation rows (V, D) of formation b at its current state."""
    nv = s.aircraft.shape[1]
    amb = np.empty((nv, 3))
    ambient_wind(p.scenario, s, b, s.step[b] * p.dt_s, amb, np.empty(3))
    sched = np.empty((nv, 10))
    schedule_features(p.scenario, s.step[b] * p.dt_s, s.slot_jitter[b], sched)
    observe_formation(s.aircraft[b], s.induced_wind_ned[b], s.induced_omega_body[b], amb, s.position_demand[b],
                      s.velocity_demand[b], s.previous_action[b], sched, s.controller[b], p.trim_airspeed_mps,
                      p.scenario.altitude_m, p.aircraft.scalars, np.empty((nv, 3)), np.empty(nv), out_obs,
                      p.neighbour_count, p.observation_switches)
