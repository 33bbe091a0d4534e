"""Compiled (numba) RK4 step of the Aerosonde: the same equations as :mod:`.eom`, one aircraft per
loop iteration, so one call serves B = 1 or B = 1024 with no per-operation numpy overhead.

:mod:`.eom` (numpy, vectorised over the batch axis) holds the readable equations; this module is
a line-by-line transcription of them, and ``tests/aircraft/test_aircraft_kernels.py`` checks it against
the numpy reference step built on :func:`.eom.derivatives` (the test oracle
``tests/oracles/aircraft_rk4.py``) to round-off. Each aircraft's arithmetic is independent of the others, so a batch reproduces B
single runs bit for bit.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba as nb
import numpy as np

from ..atmosphere.standard import atmosphere_table
from ..frames import quaternion_dcm_terms
from .params import AerosondeParams

_jit = nb.njit(cache=True, fastmath=False, error_model="numpy")
# the table lookups, inlined at numba IR level into their callers: _deriv reads the tables as fields of the packed
# model and a compiled call would take and release a reference count of each table per lookup (four derivatives an
# RK4 step, six lookups each), where inlined the reads need none
_jit_inline = nb.njit(cache=True, fastmath=False, error_model="numpy", inline="always")

# indices into the packed parameter vector
(K_MAC, K_SPAN, K_AREA, K_VA_LO, K_VA_HI, K_BE_LO, K_BE_HI, K_AL_LO, K_AL_HI,
 K_CL0, K_CLA, K_CLDF, K_CLDE, K_CLAD, K_CLQ, K_CLM,
 K_CLMIND, K_CDMIN, K_CDDF, K_CDDE, K_CDDA, K_CDDR, K_CDM, K_KIND,
 K_CYB, K_CYDA, K_CYDR, K_CYP, K_CYR,
 K_CM0, K_CMA, K_CMDF, K_CMDE, K_CMAD, K_CMQ, K_CMM,
 K_CLB, K_CLDA, K_CLDR, K_CLP, K_CLR,
 K_CNB, K_CNDA, K_CNDR, K_CNP, K_CNR,
 K_RAC0, K_RAC1, K_RAC2, K_RHUB0, K_RHUB1, K_RHUB2, K_RPROP, K_JSHAFT, K_TSL, K_MAPMIN,
 K_MEMPTY, K_FUELCAP, K_CGE0, K_CGE1, K_CGE2, K_CGG0, K_CGG1, K_CGG2,
 K_JE0, K_JE1, K_JE2, K_JE3, K_JG0, K_JG1, K_JG2, K_JG3,
 K_G, K_GMODEL, K_LAT, K_ALPHADOT, K_REACTION, K_NPARAMS) = range(78)


class AircraftTables(NamedTuple):
    """The Aerosonde model packed for :func:`rk4_batch` (:func:`pack`): the scalars and the tables."""

    scalars: np.ndarray  # (K_NPARAMS,) coefficients, geometry, mass data, options
    prop_J: np.ndarray  # propeller advance ratio breaks
    prop_CT: np.ndarray  # thrust coefficient at them
    prop_CP: np.ndarray  # power coefficient at them
    engine_rpm: np.ndarray  # engine map rows, rpm
    engine_map: np.ndarray  # engine map columns, manifold pressure kPa
    engine_power: np.ndarray  # shaft power, W
    engine_fuel: np.ndarray  # fuel flow, g/h
    atm_T: np.ndarray  # ISA table: temperature, K
    atm_P: np.ndarray  # pressure, Pa
    atm_rho: np.ndarray  # density, kg/m^3
    atm_a: np.ndarray  # speed of sound, m/s


def pack(params: AerosondeParams, options) -> AircraftTables:
    """Packed scalars and tables for the kernels (an :class:`AircraftTables`)."""
    P = params
    v = np.zeros(K_NPARAMS)
    v[[K_MAC, K_SPAN, K_AREA]] = P.mac, P.span, P.area
    v[[K_VA_LO, K_VA_HI]] = P.va_bounds
    v[[K_BE_LO, K_BE_HI]] = P.beta_bounds
    v[[K_AL_LO, K_AL_HI]] = P.alpha_bounds
    v[K_CL0:K_CLM + 1] = P.CL0, P.CLa, P.CLdf, P.CLde, P.CLalphadot, P.CLq, P.CLM
    v[K_CLMIND:K_CDM + 1] = P.CLmind, P.CDmin, P.CDdf, P.CDde, P.CDda, P.CDdr, P.CDM
    v[K_KIND] = np.pi * P.osw * P.aspect_ratio
    v[K_CYB:K_CYR + 1] = P.CYbeta, P.CYda, P.CYdr, P.CYp, P.CYr
    v[K_CM0:K_CMM + 1] = P.Cm0, P.Cma, P.Cmdf, P.Cmde, P.Cmalphadot, P.Cmq, P.CmM
    v[K_CLB:K_CLR + 1] = P.Clbeta, P.Clda, P.Cldr, P.Clp, P.Clr
    v[K_CNB:K_CNR + 1] = P.Cnbeta, P.Cnda, P.Cndr, P.Cnp, P.Cnr
    v[K_RAC0:K_RAC2 + 1] = P.r_ac_body
    v[K_RHUB0:K_RHUB2 + 1] = P.r_hub_body
    v[K_RPROP], v[K_JSHAFT], v[K_TSL], v[K_MAPMIN] = P.prop_radius, P.shaft_inertia, P.T_sl, P.map_min_kpa
    v[K_MEMPTY], v[K_FUELCAP] = P.mass_empty, P.fuel_capacity
    v[K_CGE0:K_CGE2 + 1] = P.cg_empty_body
    v[K_CGG0:K_CGG2 + 1] = P.cg_gross_body
    v[K_JE0:K_JE3 + 1] = P.inertia_empty
    v[K_JG0:K_JG3 + 1] = P.inertia_gross
    v[K_G] = options.g
    v[K_GMODEL] = 0.0 if options.gravity_model == "constant" else 1.0
    v[K_LAT] = options.latitude_rad
    v[K_ALPHADOT] = 1.0 if options.alpha_dot else 0.0
    v[K_REACTION] = 1.0 if options.engine_reaction_torque else 0.0
    tab = atmosphere_table()
    c = np.ascontiguousarray
    return AircraftTables(scalars=v, prop_J=c(P.prop_J), prop_CT=c(P.prop_CT), prop_CP=c(P.prop_CP),
                          engine_rpm=c(P.engine_rpm), engine_map=c(P.engine_map_kpa), engine_power=c(P.engine_power_w),
                          engine_fuel=c(P.engine_fuel_flow_g_per_h), atm_T=c(tab[:, 1]), atm_P=c(tab[:, 2]),
                          atm_rho=c(tab[:, 3]), atm_a=c(tab[:, 4]))


@_jit_inline
def _seg(breaks, x):
    """Segment index (end segments extrapolate) and fraction, as lookup._segment."""
    n = breaks.shape[0]
    xs = x if math.isfinite(x) else breaks[0]
    # searchsorted(side="right") - 1, clipped to [0, n - 2]
    i = 0
    while i < n - 2 and breaks[i + 1] <= xs:
        i += 1
    return i, (x - breaks[i]) / (breaks[i + 1] - breaks[i])


@_jit_inline
def _interp1(breaks, values, x):
    i, f = _seg(breaks, x)
    return values[i] + f * (values[i + 1] - values[i])


@_jit_inline
def _interp2(rows, cols, table, xr, xc):
    i, fr = _seg(rows, xr)
    j, fc = _seg(cols, xc)
    return ((1.0 - fr) * ((1.0 - fc) * table[i, j] + fc * table[i, j + 1])
            + fr * ((1.0 - fc) * table[i + 1, j] + fc * table[i + 1, j + 1]))


@_jit
def _clip(x, lo, hi):
    # np.clip semantics, NaN propagates
    if x < lo:
        return lo
    if x > hi:
        return hi
    return x


@_jit
def _zo(x):
    if abs(x) >= 1e-6:
        return x
    return -1e-6 if x < 0.0 else 1e-6


@_jit_inline
def _atmos(alt, tT, tP, tR, tA):
    h = _clip(alt, 0.0, 86000.0) / 100.0
    if not math.isfinite(h):
        return math.nan, math.nan, math.nan, math.nan
    i = min(int(h), tT.shape[0] - 2)
    f = h - i
    return (tT[i] + f * (tT[i + 1] - tT[i]), tP[i] + f * (tP[i + 1] - tP[i]),
            tR[i] + f * (tR[i + 1] - tR[i]), tA[i] + f * (tA[i + 1] - tA[i]))


@_jit
def air_data_kernel(x, wind, v):
    """Raw and clipped air data of one aircraft (compiled; the numpy form is :func:`.eom.air_data_of`).

    x (16,) the state (:mod:`.state` layout: body velocity m/s, quaternion body to NED, ...);
    wind (12,) = [ambient wind NED (3) m/s, turbulence body axes (3) m/s, ELL induced wind NED (3)
    m/s, ELL rotational wind body (3) rad/s]; v (K_NPARAMS,) the packed scalars (:func:`pack`).
    Returns the 15-tuple (airspeed m/s, alpha rad, beta rad as computed, the same three clipped to
    the model's table bounds, then r00, r01, r02, r10, ..., r22 of the body-to-NED matrix)."""
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = quaternion_dcm_terms(x[6], x[7], x[8], x[9])
    wn = wind[0] + wind[6]
    we = wind[1] + wind[7]
    wd = wind[2] + wind[8]
    ur = x[0] - ((r00 * wn + r10 * we + r20 * wd) + wind[3])
    vr = x[1] - ((r01 * wn + r11 * we + r21 * wd) + wind[4])
    wr = x[2] - ((r02 * wn + r12 * we + r22 * wd) + wind[5])
    va_raw = math.sqrt(ur * ur + vr * vr + wr * wr)
    alpha_raw = math.atan(wr / _zo(ur))
    beta_raw = math.asin(_clip(vr / _zo(va_raw), -1.0, 1.0))
    return (va_raw, alpha_raw, beta_raw, _clip(va_raw, v[K_VA_LO], v[K_VA_HI]),
            _clip(alpha_raw, v[K_AL_LO], v[K_AL_HI]), _clip(beta_raw, v[K_BE_LO], v[K_BE_HI]),
            r00, r01, r02, r10, r11, r12, r20, r21, r22)


@_jit
def aero_body(c, nctrl, va, alpha, beta, mach, qbar, ad, pa, qa, ra, v):
    """Aerodynamic force (N, body axes) and moment (N m, body axes, about the aerodynamic centre) of one
    aircraft: AeroSim's coefficient build-up in wind axes rotated to body axes (as
    :func:`.aerodynamics.aero_coefficients` and :func:`.aerodynamics.aero_forces_moments`). c the controls
    (elevator, aileron, rudder, throttle[, flap]) of which the first ``nctrl`` exist; va, alpha, beta the
    clipped air data; ad alpha-dot, rad/s; pa, qa, ra the aerodynamic rates (body rates minus the
    rotational wind), rad/s. Returns (fx, fy, fz, mx, my, mz)."""
    de, da, dr = c[0], c[1], c[2]
    df = c[4] if nctrl > 4 else 0.0
    c2v = v[K_MAC] / (2.0 * va)
    b2v = v[K_SPAN] / (2.0 * va)
    CL = (v[K_CL0] + v[K_CLA] * alpha + v[K_CLDF] * df + v[K_CLDE] * de
          + (v[K_CLAD] * ad + v[K_CLQ] * qa) * c2v + v[K_CLM] * mach)
    CD = (v[K_CDMIN] + (CL - v[K_CLMIND]) ** 2 / v[K_KIND]
          + abs(v[K_CDDF] * df) + abs(v[K_CDDE] * de) + abs(v[K_CDDA] * da)
          + abs(v[K_CDDR] * dr) + v[K_CDM] * mach)
    CY = v[K_CYB] * beta + v[K_CYDA] * da + v[K_CYDR] * dr + (v[K_CYP] * pa + v[K_CYR] * ra) * b2v
    Cl = v[K_CLB] * beta + v[K_CLDA] * da + v[K_CLDR] * dr + (v[K_CLP] * pa + v[K_CLR] * ra) * b2v
    Cm = (v[K_CM0] + v[K_CMA] * alpha + v[K_CMDF] * df + v[K_CMDE] * de
          + (v[K_CMAD] * ad + v[K_CMQ] * qa) * c2v + v[K_CMM] * mach)
    Cn = v[K_CNB] * beta + v[K_CNDA] * da + v[K_CNDR] * dr + (v[K_CNP] * pa + v[K_CNR] * ra) * b2v
    qs = qbar * v[K_AREA]
    fxw, fyw, fzw = -qs * CD, qs * CY, -qs * CL
    ca, sa, cb, sb = math.cos(alpha), math.sin(alpha), math.cos(beta), math.sin(beta)
    fx = ca * cb * fxw - ca * sb * fyw - sa * fzw
    fy = sb * fxw + cb * fyw
    fz = sa * cb * fxw - sa * sb * fyw + ca * fzw
    mx = qs * v[K_SPAN] * Cl
    my = qs * v[K_MAC] * Cm
    mz = qs * v[K_SPAN] * Cn
    return fx, fy, fz, mx, my, mz


@_jit
def air_density_at(altitude_m, tT, tP, tR, tA):
    """ISA density (kg/m^3) at ``altitude_m`` from the packed atmosphere table (as the RK4 uses it)."""
    return _atmos(altitude_m, tT, tP, tR, tA)[2]


@_jit
def aero_force_at(x, c, wind, v, tT, tP, tR, tA):
    """The aerodynamic force (N, body axes) of one aircraft at state x (16,) with controls c and the
    wind 12-vector ``wind`` (:func:`air_data_kernel`'s), quasi-steady (alpha-dot 0): what :func:`rk4_batch`
    applies at that instant apart from the alpha-dot term. Returns (fx, fy, fz)."""
    (va_raw, alpha_raw, beta_raw, va, alpha, beta,
     r00, r01, r02, r10, r11, r12, r20, r21, r22) = air_data_kernel(x, wind, v)
    temp, pres, rho, sound = _atmos(-x[12], tT, tP, tR, tA)
    fx, fy, fz, mx, my, mz = aero_body(c, c.shape[0], va, alpha, beta, va_raw / sound, 0.5 * rho * va * va, 0.0,
                                       x[3] - wind[9], x[4] - wind[10], x[5] - wind[11], v)
    return fx, fy, fz


@_jit_inline
def _deriv(x, c, nctrl, wind, alphadot, ac, out):
    """State derivative (15,) of one aircraft into ``out``; ``ac`` the packed model (:class:`AircraftTables`, or
    any struct with its fields: one argument rather than twelve arrays). Inlined at numba IR level into
    :func:`rk4_batch`'s one call site: a compiled call would take and release a reference count of each array
    argument, four derivatives an RK4 step."""
    v = ac.scalars
    u, vv, w = x[0], x[1], x[2]
    p, q, r = x[3], x[4], x[5]
    fuel = _clip(x[13], 0.0, v[K_FUELCAP])
    omega = x[14]
    thr = c[3]
    (va_raw, alpha_raw, beta_raw, va, alpha, beta,
     r00, r01, r02, r10, r11, r12, r20, r21, r22) = air_data_kernel(x, wind, v)
    alt = -x[12]
    temp, pres, rho, sound = _atmos(alt, ac.atm_T, ac.atm_P, ac.atm_rho, ac.atm_a)
    if v[K_GMODEL] == 0.0:
        g = v[K_G]
    else:
        s2 = math.sin(v[K_LAT]) ** 2
        e2 = 0.0818191908426 ** 2
        g = (9.7803267714 * (1.0 + 0.00193185138639 * s2) / math.sqrt(1.0 - e2 * s2)
             - (3.0877e-6 - 0.0044e-6 * s2) * alt + 0.072e-12 * alt * alt)
    mach = va_raw / sound
    qbar = 0.5 * rho * va * va
    pa = p - wind[9]
    qa = q - wind[10]
    ra = r - wind[11]
    ad = alphadot if v[K_ALPHADOT] != 0.0 else 0.0
    fx, fy, fz, mx, my, mz = aero_body(c, nctrl, va, alpha, beta, mach, qbar, ad, pa, qa, ra, v)
    # propeller
    om = max(omega, 1.0) if math.isfinite(omega) else omega
    rad = v[K_RPROP]
    adv = math.pi * va / (om * rad)
    ct = _interp1(ac.prop_J, ac.prop_CT, adv)
    cp = _interp1(ac.prop_J, ac.prop_CP, adv)
    rho_om2 = rho * om * om
    thrust = (4.0 / math.pi ** 2) * rad ** 4 * rho_om2 * ct
    q_prop = -(4.0 / math.pi ** 3) * rad ** 5 * rho_om2 * cp
    # engine
    mapmin = v[K_MAPMIN]
    map_kpa = mapmin + thr * (pres / 1000.0 - mapmin)
    if not map_kpa >= mapmin:  # np.maximum: NaN propagates
        map_kpa = mapmin if math.isfinite(map_kpa) else map_kpa
    rpm = om * (30.0 / math.pi)
    power = _interp2(ac.engine_rpm, ac.engine_map, ac.engine_power, rpm, map_kpa) * math.sqrt(v[K_TSL] / temp)
    q_eng = power / om
    fuel_flow = _interp2(ac.engine_rpm, ac.engine_map, ac.engine_fuel, rpm, map_kpa) / 3.6e6
    on = 1.0 if fuel > 0.0 else 0.0
    omega_dot = (on * q_eng + q_prop) / v[K_JSHAFT]
    if omega <= 0.0 and omega_dot < 0.0:
        omega_dot = 0.0
    # mass properties
    frac = fuel / v[K_FUELCAP]
    mass = v[K_MEMPTY] + fuel
    cg0 = v[K_CGE0] + frac * (v[K_CGG0] - v[K_CGE0])
    cg1 = v[K_CGE1] + frac * (v[K_CGG1] - v[K_CGE1])
    cg2 = v[K_CGE2] + frac * (v[K_CGG2] - v[K_CGE2])
    jx = v[K_JE0] + frac * (v[K_JG0] - v[K_JE0])
    jy = v[K_JE1] + frac * (v[K_JG1] - v[K_JE1])
    jz = v[K_JE2] + frac * (v[K_JG2] - v[K_JE2])
    jxz = v[K_JE3] + frac * (v[K_JG3] - v[K_JE3])
    a0, a1, a2 = v[K_RAC0] - cg0, v[K_RAC1] - cg1, v[K_RAC2] - cg2
    h1, h2 = v[K_RHUB1] - cg1, v[K_RHUB2] - cg2
    L = mx + a1 * fz - a2 * fy
    M = my + a2 * fx - a0 * fz + h2 * thrust
    N = mz + a0 * fy - a1 * fx - h1 * thrust
    if v[K_REACTION] != 0.0:
        L = L - on * q_eng
    ax = (fx + thrust) / mass + g * r20
    ay = fy / mass + g * r21
    az = fz / mass + g * r22
    out[0] = r * vv - q * w + ax
    out[1] = p * w - r * u + ay
    out[2] = q * u - p * vv + az
    gam = jx * jz - jxz * jxz
    c1 = ((jy - jz) * jz - jxz * jxz) / gam
    c2 = (jx - jy + jz) * jxz / gam
    c3 = jz / gam
    c4 = jxz / gam
    c5 = (jz - jx) / jy
    c6 = jxz / jy
    c7 = 1.0 / jy
    c8 = (jx * (jx - jy) + jxz * jxz) / gam
    c9 = jx / gam
    out[3] = (c1 * r + c2 * p) * q + c3 * L + c4 * N
    out[4] = c5 * p * r - c6 * (p * p - r * r) + c7 * M
    out[5] = (c8 * p - c2 * r) * q + c4 * L + c9 * N
    norm = math.sqrt(x[6] * x[6] + x[7] * x[7] + x[8] * x[8] + x[9] * x[9])
    e0, ex, ey, ez = x[6] / norm, x[7] / norm, x[8] / norm, x[9] / norm
    out[6] = 0.5 * (-p * ex - q * ey - r * ez)
    out[7] = 0.5 * (p * e0 + r * ey - q * ez)
    out[8] = 0.5 * (q * e0 - r * ex + p * ez)
    out[9] = 0.5 * (r * e0 + q * ex - p * ey)
    out[10] = r00 * u + r01 * vv + r02 * w
    out[11] = r10 * u + r11 * vv + r12 * w
    out[12] = r20 * u + r21 * vv + r22 * w
    out[13] = -fuel_flow * on
    out[14] = omega_dot


@_jit
def rk4_batch(state, controls, wind, dt, ac, out):
    """RK4 step of B aircraft: state (B, 16), controls (B, 4|5), wind (B, 12), ``ac`` the packed model
    (:class:`AircraftTables` or a struct with its fields); the new state into ``out`` (B, 16; another array than
    ``state``), which is returned."""
    n = state.shape[0]
    nctrl = controls.shape[1]
    v = ac.scalars
    work = np.empty((5, 15))  # k1..k4 and the stage state
    xs = work[4]
    for b in range(n):
        x = state[b]
        c = controls[b]
        wb = wind[b]
        alpha_now = air_data_kernel(x, wb, v)[1]
        alphadot = (alpha_now - x[15]) / dt if v[K_ALPHADOT] != 0.0 else 0.0
        # the four stages through one call site of the inlined _deriv (one copy of its body, not four)
        for st in range(4):
            for i in range(15):
                if st == 0:
                    xs[i] = x[i]
                elif st == 3:
                    xs[i] = x[i] + dt * work[2, i]
                else:
                    xs[i] = x[i] + (0.5 * dt) * work[st - 1, i]
            _deriv(xs, c, nctrl, wb, alphadot, ac, work[st])
        for i in range(15):
            out[b, i] = x[i] + (dt / 6.0) * (work[0, i] + 2.0 * (work[1, i] + work[2, i]) + work[3, i])
        qn = math.sqrt(out[b, 6] ** 2 + out[b, 7] ** 2 + out[b, 8] ** 2 + out[b, 9] ** 2)
        for i in range(6, 10):
            out[b, i] = out[b, i] / qn
        out[b, 13] = _clip(out[b, 13], 0.0, v[K_FUELCAP])
        out[b, 14] = max(out[b, 14], 0.0) if math.isfinite(out[b, 14]) else out[b, 14]
        out[b, 15] = alpha_now
    return out
