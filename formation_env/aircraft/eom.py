"""Equations of motion of the Aerosonde (AeroSim body-frame 6-DOF, flat non-rotating Earth)
and the fixed-step RK4 integrator.

Everything works on a leading batch axis: B aircraft in one call, one code path for B = 1 and
B = 1024. All arithmetic is row-wise (no matrix products that could change with B), so a batch
gives bit-for-bit the same numbers as B single runs.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .. import frames
from ..atmosphere.gravity import gravity_wgs84
from ..atmosphere.standard import standard_atmosphere
from ..atmosphere.wind import WindInput
from .aerodynamics import aero_coefficients, aero_forces_moments, air_data
from .mass import mass_properties
from .params import AEROSONDE, AerosondeParams
from .propulsion import engine, propeller
from .state import ALPHA_PREV, FUEL, N_INTEGRATED, N_STATES, OMEGA, POS, QUAT, RATES, VEL, as_state

__all__ = [
    "ModelOptions", "DEFAULT_OPTIONS", "derivatives", "step", "validate_controls",
    "air_data_of", "outputs", "N_CONTROLS", "make_state",
]

N_CONTROLS = 4  # elevator, aileron, rudder, throttle; a 5th column is the flap


@dataclass(frozen=True)
class ModelOptions:
    """Switches of the model. The defaults reproduce the thesis trim (Table A.5).

    gravity_model: "constant" (``g``, 9.81 reproduces the thesis) or "wgs84" (normal gravity at
        ``latitude_rad`` and the current altitude).
    alpha_dot: include the alpha-dot terms of CL and Cm. In ``step`` alpha-dot is AeroSim's
        backward difference of the raw angle of attack between steps.
    engine_reaction_torque: apply the engine reaction torque ``-Q_eng`` about body x (AeroSim
        does). Switching it off makes the aircraft laterally symmetric (used in tests).
    """

    gravity_model: str = "constant"
    g: float = 9.81
    latitude_rad: float = float(np.deg2rad(45.0))
    alpha_dot: bool = True
    engine_reaction_torque: bool = True

    def __post_init__(self) -> None:
        if self.gravity_model not in ("constant", "wgs84"):
            raise ValueError(f"ModelOptions.gravity_model must be 'constant' or 'wgs84', got {self.gravity_model!r}")
        if not (np.isfinite(self.g) and self.g > 0.0):
            raise ValueError(f"ModelOptions.g must be positive, got {self.g!r}")
        if not (np.isfinite(self.latitude_rad) and abs(self.latitude_rad) <= np.pi / 2):
            raise ValueError(f"ModelOptions.latitude_rad must be in [-pi/2, pi/2], got {self.latitude_rad!r}")


DEFAULT_OPTIONS = ModelOptions()


def validate_controls(controls, batch_size: int) -> np.ndarray:
    """Controls as a float (B, 4) or (B, 5) array ``[elevator, aileron, rudder, throttle(, flap)]``.

    Raises ValueError on a wrong shape or on NaN/inf. No clipping here: AeroSim clips nothing
    (use :mod:`.actuators` for limits).
    """
    arr = np.asarray(controls, dtype=float)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] not in (4, 5) or arr.shape[0] not in (1, batch_size):
        raise ValueError(
            f"controls must have shape ({batch_size}, 4) [elevator, aileron, rudder, throttle] "
            f"or ({batch_size}, 5) with flap last, got {np.shape(controls)}"
        )
    if not np.all(np.isfinite(arr)):
        bad = np.flatnonzero(~np.all(np.isfinite(arr), axis=1))
        raise ValueError(f"controls contain NaN or inf (aircraft {bad.tolist()})")
    if arr.shape[0] != batch_size:
        arr = np.broadcast_to(arr, (batch_size, arr.shape[1]))
    return arr


def _wind(wind: WindInput | None, n: int) -> WindInput:
    if wind is None:
        return WindInput.zeros(n)
    if not isinstance(wind, WindInput):
        raise ValueError("wind must be a WindInput (or None for still air)")
    return wind.for_batch(n)


def _rotation_terms(quat: np.ndarray):
    """Body-to-NED matrix entries from the stored quaternion, as a tuple of (B,) arrays
    R[i][j] (row i = NED axis, column j = body axis)."""
    e0, ex, ey, ez = quat[:, 0], quat[:, 1], quat[:, 2], quat[:, 3]
    r00 = e0 * e0 + ex * ex - ey * ey - ez * ez
    r01 = 2.0 * (ex * ey - e0 * ez)
    r02 = 2.0 * (ex * ez + e0 * ey)
    r10 = 2.0 * (ex * ey + e0 * ez)
    r11 = e0 * e0 - ex * ex + ey * ey - ez * ez
    r12 = 2.0 * (ey * ez - e0 * ex)
    r20 = 2.0 * (ex * ez - e0 * ey)
    r21 = 2.0 * (ey * ez + e0 * ex)
    r22 = e0 * e0 - ex * ex - ey * ey + ez * ez
    return ((r00, r01, r02), (r10, r11, r12), (r20, r21, r22))


def _ned_to_body(R, vec_ned: np.ndarray) -> np.ndarray:
    """C_bn v = R^T v, row by row."""
    x, y, z = vec_ned[:, 0], vec_ned[:, 1], vec_ned[:, 2]
    return np.stack(
        [R[0][0] * x + R[1][0] * y + R[2][0] * z,
         R[0][1] * x + R[1][1] * y + R[2][1] * z,
         R[0][2] * x + R[1][2] * y + R[2][2] * z],
        axis=-1,
    )


def _relative_velocity(x: np.ndarray, R, wind: WindInput) -> np.ndarray:
    wind_body = _ned_to_body(R, wind.wind_ned + wind.ell_translational_ned) + wind.turbulence_body
    return x[:, 0:3] - wind_body


def air_data_of(state, wind: WindInput | None = None, params: AerosondeParams = AEROSONDE) -> dict:
    """Air data of each aircraft: raw and clipped airspeed, alpha, beta (B,) arrays."""
    s = as_state(state) if np.shape(state)[-1] == N_STATES else np.atleast_2d(np.asarray(state, float))
    w = _wind(wind, s.shape[0])
    R = _rotation_terms(s[:, QUAT])
    va_raw, alpha_raw, beta_raw, va, alpha, beta = air_data(_relative_velocity(s, R, w), params)
    return {"airspeed_raw": va_raw, "alpha_raw": alpha_raw, "beta_raw": beta_raw,
            "airspeed": va, "alpha": alpha, "beta": beta}


def _broadcast(x, n: int, width: int | None, name: str) -> np.ndarray:
    arr = np.asarray(x, dtype=float)
    shape = (n,) if width is None else (n, width)
    try:
        return np.broadcast_to(arr, shape)
    except ValueError:
        raise ValueError(f"make_state: {name} cannot be broadcast to {shape}, got {arr.shape}") from None


def make_state(velocity_body, rates_body=(0.0, 0.0, 0.0), euler_rad=(0.0, 0.0, 0.0),
               position_ned=(0.0, 0.0, -1000.0), fuel_kg=2.0, omega_rad_s=5000 * np.pi / 30,
               wind=None, batch_size: int | None = None) -> np.ndarray:
    """Build a (B, N_STATES) state (the layout of :mod:`formation_env.aircraft.state`). Vectors are (3,) or (B, 3);
    scalars or (B,).

    ``wind`` (a :class:`~formation_env.atmosphere.WindInput`) is used only to initialise the
    alpha-dot memory so that alpha-dot is 0 on the first step, as AeroSim's Derivative block is.
    """
    cands = [np.asarray(v) for v in (velocity_body, rates_body, euler_rad, position_ned)]
    n = batch_size or max([c.shape[0] if c.ndim == 2 else 1 for c in cands]
                          + [np.size(fuel_kg), np.size(omega_rad_s)])
    s = np.zeros((n, N_STATES))
    s[:, VEL] = _broadcast(velocity_body, n, 3, "velocity_body")
    s[:, RATES] = _broadcast(rates_body, n, 3, "rates_body")
    s[:, QUAT] = frames.quaternion_from_euler(_broadcast(euler_rad, n, 3, "euler_rad"))
    s[:, POS] = _broadcast(position_ned, n, 3, "position_ned")
    s[:, FUEL] = _broadcast(fuel_kg, n, None, "fuel_kg")
    s[:, OMEGA] = _broadcast(omega_rad_s, n, None, "omega_rad_s")
    s[:, ALPHA_PREV] = air_data_of(s, wind)["alpha_raw"]
    return s


def derivatives(x, controls, wind: WindInput | None, alphadot, params: AerosondeParams = AEROSONDE,
                options: ModelOptions = DEFAULT_OPTIONS, want_outputs: bool = False):
    """Time derivative of the integrated states (first N_INTEGRATED = 15 columns of ``x``).

    ``controls`` (B, 4|5) validated; ``wind`` held; ``alphadot`` (B,) or scalar, the alpha-dot
    fed to CL and Cm. Returns ``xdot`` (B, 15), or ``(xdot, outputs_dict)`` when ``want_outputs``.
    """
    n = x.shape[0]
    if wind is None or wind.batch_size != n:
        wind = _wind(wind, n)
    u, v, w = x[:, 0], x[:, 1], x[:, 2]
    p, q, r = x[:, 3], x[:, 4], x[:, 5]
    quat = x[:, QUAT]
    fuel = np.clip(x[:, FUEL], 0.0, params.fuel_capacity)
    omega = x[:, OMEGA]
    de, da, dr, thr = controls[:, 0], controls[:, 1], controls[:, 2], controls[:, 3]
    df = controls[:, 4] if controls.shape[1] > 4 else 0.0

    R = _rotation_terms(quat)
    alt = -x[:, 12]
    temp, pres, rho, sound = standard_atmosphere(alt)
    if options.gravity_model == "constant":
        g = options.g
    else:
        g = gravity_wgs84(options.latitude_rad, alt)

    # --- air data (thesis Eq. 4.8: air-relative velocity = ground velocity - wind) ----------
    va_raw, alpha_raw, beta_raw, va, alpha, beta = air_data(_relative_velocity(x, R, wind), params)
    mach = va_raw / sound
    qbar = 0.5 * rho * va * va
    # thesis Eq. 4.9: the aerodynamics see the body rates minus the rotational wind
    pa = p - wind.ell_rotational_body[:, 0]
    qa = q - wind.ell_rotational_body[:, 1]
    ra = r - wind.ell_rotational_body[:, 2]
    ad = alphadot if options.alpha_dot else 0.0
    CD, CY, CL, Cl, Cm, Cn = aero_coefficients(alpha, beta, va, mach, ad, pa, qa, ra, df, de, da, dr, params)
    f_aero, m_ac = aero_forces_moments(CD, CY, CL, Cl, Cm, Cn, qbar, alpha, beta, params)

    # --- propulsion --------------------------------------------------------------------------
    thrust, q_prop, adv, ct, cp = propeller(va, rho, omega, params)
    map_kpa, power, q_eng, fuel_flow = engine(thr, pres, temp, omega, params)
    on = (fuel > 0.0).astype(float)  # ignition always on; the engine stops when the tank is empty
    omega_dot = (on * q_eng + q_prop) / params.shaft_inertia
    omega_dot = np.where((omega <= 0.0) & (omega_dot < 0.0), 0.0, omega_dot)  # integrator limit >= 0
    fuel_dot = -fuel_flow * on

    # --- mass properties and moments about the CG --------------------------------------------
    mass, cg, inertia = mass_properties(fuel, params)
    arm_ac = params.r_ac_body - cg
    arm_hub = params.r_hub_body - cg
    fx, fy, fz = f_aero[:, 0], f_aero[:, 1], f_aero[:, 2]
    L = m_ac[:, 0] + arm_ac[:, 1] * fz - arm_ac[:, 2] * fy
    M = m_ac[:, 1] + arm_ac[:, 2] * fx - arm_ac[:, 0] * fz + arm_hub[:, 2] * thrust
    N = m_ac[:, 2] + arm_ac[:, 0] * fy - arm_ac[:, 1] * fx - arm_hub[:, 1] * thrust
    if options.engine_reaction_torque:
        L = L - on * q_eng

    # --- translational dynamics (gravity along NED +z) ----------------------------------------
    ax = (fx + thrust) / mass + g * R[2][0]
    ay = fy / mass + g * R[2][1]
    az = fz / mass + g * R[2][2]
    xdot = np.empty((n, N_INTEGRATED))
    xdot[:, 0] = r * v - q * w + ax
    xdot[:, 1] = p * w - r * u + ay
    xdot[:, 2] = q * u - p * v + az

    # --- rotational dynamics (Stevens & Lewis, Jxz positive product) ---------------------------
    jx, jy, jz, jxz = inertia[:, 0], inertia[:, 1], inertia[:, 2], inertia[:, 3]
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
    xdot[:, 3] = (c1 * r + c2 * p) * q + c3 * L + c4 * N
    xdot[:, 4] = c5 * p * r - c6 * (p * p - r * r) + c7 * M
    xdot[:, 5] = (c8 * p - c2 * r) * q + c4 * L + c9 * N

    # --- attitude: the derivative uses the normalised quaternion (AeroSim) ---------------------
    norm = np.sqrt(np.sum(quat * quat, axis=1))
    e0, ex, ey, ez = (quat[:, k] / norm for k in range(4))
    xdot[:, 6] = 0.5 * (-p * ex - q * ey - r * ez)
    xdot[:, 7] = 0.5 * (p * e0 + r * ey - q * ez)
    xdot[:, 8] = 0.5 * (q * e0 - r * ex + p * ez)
    xdot[:, 9] = 0.5 * (r * e0 + q * ex - p * ey)

    # --- flat-earth navigation ---------------------------------------------------------------
    xdot[:, 10] = R[0][0] * u + R[0][1] * v + R[0][2] * w
    xdot[:, 11] = R[1][0] * u + R[1][1] * v + R[1][2] * w
    xdot[:, 12] = R[2][0] * u + R[2][1] * v + R[2][2] * w
    xdot[:, 13] = fuel_dot
    xdot[:, 14] = omega_dot
    if not want_outputs:
        return xdot
    out = {
        "airspeed": va, "alpha": alpha, "beta": beta, "airspeed_raw": va_raw, "alpha_raw": alpha_raw,
        "beta_raw": beta_raw, "mach": mach, "qbar": qbar, "rho": rho, "temperature": temp,
        "pressure": pres, "g": np.broadcast_to(g, (n,)),
        "CD": CD, "CY": CY, "CL": CL, "Cl": Cl, "Cm": Cm, "Cn": Cn,
        "force_aero_body": f_aero, "moment_cg_body": np.stack([L, M, N], axis=-1),
        "thrust": thrust, "prop_torque": q_prop, "advance_ratio": adv, "CT": ct, "CP": cp,
        "map_kpa": map_kpa, "power": power * on, "engine_torque": q_eng * on, "fuel_flow": fuel_flow * on,
        "mass": mass, "cg_body": cg, "inertia": inertia,
        "specific_force_body": np.stack([(fx + thrust) / mass, fy / mass, fz / mass], axis=-1),
    }
    return xdot, out


def _check_dt(dt) -> float:
    dt = float(dt)
    if not (np.isfinite(dt) and dt > 0.0):
        raise ValueError(f"dt must be positive and finite, got {dt!r}")
    return dt


@lru_cache(maxsize=16)
def _packed(params: AerosondeParams, options: ModelOptions):
    from .kernels import pack

    return pack(params, options)


BACKENDS = ("numba",)  # the numpy reference of the step is a test oracle: tests/oracles/aircraft_rk4.py


def step(state, controls, wind: WindInput | None = None, dt: float = 0.02,
         params: AerosondeParams = AEROSONDE, options: ModelOptions = DEFAULT_OPTIONS,
         backend: str = "numba") -> np.ndarray:
    """Advance B aircraft by one fixed RK4 step of ``dt`` seconds; a pure function.

    ``state`` (B, 16), ``controls`` (B, 4|5) held over the step, ``wind`` a WindInput (or None)
    held over the step. Returns the new state. Non-finite or wrongly shaped controls raise
    ValueError; a diverging aircraft is *not* an error here (its row may become non-finite
    without affecting the others): call :func:`~formation_env.aircraft.envelope.check_envelope`.

    alpha-dot is AeroSim's Derivative block: the backward difference of the raw angle of attack
    between successive steps, held over the step's RK4 stages. The quaternion is renormalised
    after each step (AeroSim does not; it keeps the DCM orthonormal over long RL episodes).

    ``backend``: "numba", the compiled kernel (:func:`.kernels.rk4_batch`), the only one. Its numpy
    reference, the same step composed from :func:`derivatives`, is the test oracle
    ``tests/oracles/aircraft_rk4.py``; the tests hold the two equal to round-off.
    """
    s = as_state(state)
    n = s.shape[0]
    u = validate_controls(controls, n)
    wnd = _wind(wind, n)
    dt = _check_dt(dt)
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r} (the numpy reference step is the "
                         "test oracle tests/oracles/aircraft_rk4.py)")
    from .kernels import rk4_batch

    wind_arr = np.concatenate(
        [wnd.wind_ned, wnd.turbulence_body, wnd.ell_translational_ned, wnd.ell_rotational_body], axis=1)
    s = np.ascontiguousarray(s)
    return rk4_batch(s, np.ascontiguousarray(u), wind_arr, dt, _packed(params, options), np.empty_like(s))


def outputs(state, controls, wind: WindInput | None = None, params: AerosondeParams = AEROSONDE,
            options: ModelOptions = DEFAULT_OPTIONS, alphadot=0.0) -> dict:
    """Derived quantities of each aircraft (air data, coefficients, engine, mass, Euler angles).

    A diagnostic, not part of the integration; ``alphadot`` defaults to 0.
    """
    s = as_state(state)
    n = s.shape[0]
    u = validate_controls(controls, n)
    xdot, out = derivatives(s[:, :N_INTEGRATED], u, _wind(wind, n), alphadot, params, options, want_outputs=True)
    out["state_dot"] = xdot
    out["euler"] = frames.euler_from_quaternion(s[:, QUAT])
    out["altitude"] = -s[:, 12]
    out["velocity_ned"] = xdot[:, POS]
    return out
