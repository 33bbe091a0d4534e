"""Numerical linearisation about a trim and modal analysis (thesis section A.1.2).

The linear model uses the 14 states of the thesis's trim model (Euler angles in place of the
quaternion, no alpha-dot memory):

    x = [u v w p q r phi theta psi north east down fuel omega],  u = [elevator aileron rudder throttle]

A and B are central differences of the nonlinear derivatives (still air). Two treatments of
alpha-dot are offered:

* ``alpha_dot="omit"`` (default): the alpha-dot terms contribute nothing, as Simulink's linmod
  does with the Derivative block that makes alpha-dot in AeroSim. This reproduces Tables A.6/A.7.
* ``alpha_dot="include"``: alpha-dot = d/dt atan(w/u) evaluated from the state derivative itself
  (the implicit equation is solved by fixed-point iteration): the physically complete model.

Longitudinal/lateral split as in the thesis (Eq. A.8, A.13): longitudinal states
[u w q theta down north omega] with inputs [elevator throttle]; lateral states
[v phi psi p r east] with inputs [aileron rudder].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import frames
from .eom import DEFAULT_OPTIONS, ModelOptions, derivatives
from .params import AEROSONDE, AerosondeParams
from .state import N_INTEGRATED, QUAT
from .trim import TrimResult, trim

__all__ = [
    "LIN_STATES", "LIN_INPUTS", "LONGITUDINAL_STATES", "LONGITUDINAL_INPUTS", "LATERAL_STATES",
    "LATERAL_INPUTS", "LinearModel", "Mode", "linearise", "modal_analysis", "name_longitudinal_modes",
    "name_lateral_modes", "open_loop_modes",
]

LIN_STATES = ("u", "v", "w", "p", "q", "r", "phi", "theta", "psi", "north", "east", "down", "fuel", "omega")
LIN_INPUTS = ("elevator", "aileron", "rudder", "throttle")
LONGITUDINAL_STATES = ("u", "w", "q", "theta", "down", "north", "omega")
LONGITUDINAL_INPUTS = ("elevator", "throttle")
LATERAL_STATES = ("v", "phi", "psi", "p", "r", "east")
LATERAL_INPUTS = ("aileron", "rudder")


def _to_full(xe: np.ndarray) -> np.ndarray:
    """(B, 14) Euler-form states -> (B, 15) integrated states with the quaternion."""
    x = np.empty((xe.shape[0], N_INTEGRATED))
    x[:, 0:6] = xe[:, 0:6]
    x[:, QUAT] = frames.quaternion_from_euler(xe[:, 6:9])
    x[:, 10:15] = xe[:, 9:14]
    return x


def euler_form_derivatives(xe, controls, params: AerosondeParams = AEROSONDE,
                           options: ModelOptions = DEFAULT_OPTIONS, alpha_dot: str = "omit") -> np.ndarray:
    """Derivative of the 14 Euler-form states, (B, 14), in still air."""
    xe = np.atleast_2d(np.asarray(xe, dtype=float))
    controls = np.atleast_2d(np.asarray(controls, dtype=float))
    x = _to_full(xe)
    if alpha_dot == "omit":
        xdot = derivatives(x, controls, None, 0.0, params, options)
    elif alpha_dot == "include":
        ad = np.zeros(xe.shape[0])
        u, w = x[:, 0], x[:, 2]
        for _ in range(100):
            xdot = derivatives(x, controls, None, ad, params, options)
            ad_new = (u * xdot[:, 2] - w * xdot[:, 0]) / (u * u + w * w)
            if np.all(np.abs(ad_new - ad) <= 1e-15 * (1.0 + np.abs(ad))):
                ad = ad_new
                break
            ad = ad_new
        xdot = derivatives(x, controls, None, ad, params, options)
    else:
        raise ValueError(f"alpha_dot must be 'omit' or 'include', got {alpha_dot!r}")
    phi, theta = xe[:, 6], xe[:, 7]
    p, q, r = xe[:, 3], xe[:, 4], xe[:, 5]
    out = np.empty_like(xe)
    out[:, 0:6] = xdot[:, 0:6]
    out[:, 6] = p + np.tan(theta) * (q * np.sin(phi) + r * np.cos(phi))
    out[:, 7] = q * np.cos(phi) - r * np.sin(phi)
    out[:, 8] = (q * np.sin(phi) + r * np.cos(phi)) / np.cos(theta)
    out[:, 9:14] = xdot[:, 10:15]
    return out


@dataclass(frozen=True, eq=False)
class LinearModel:
    """``x_dot = A dx + B du`` about ``(x0, u0)``; names label the rows/columns."""

    A: np.ndarray
    B: np.ndarray
    x0: np.ndarray
    u0: np.ndarray
    state_names: tuple[str, ...] = LIN_STATES
    input_names: tuple[str, ...] = LIN_INPUTS
    alpha_dot: str = "omit"

    def subsystem(self, states, inputs) -> "LinearModel":
        si = [self.state_names.index(s) for s in states]
        ui = [self.input_names.index(u) for u in inputs]
        return LinearModel(self.A[np.ix_(si, si)], self.B[np.ix_(si, ui)], self.x0[si], self.u0[ui],
                           tuple(states), tuple(inputs), self.alpha_dot)

    def longitudinal(self) -> "LinearModel":
        return self.subsystem(LONGITUDINAL_STATES, LONGITUDINAL_INPUTS)

    def lateral(self) -> "LinearModel":
        return self.subsystem(LATERAL_STATES, LATERAL_INPUTS)


def linearise(trim_result: TrimResult | None = None, params: AerosondeParams = AEROSONDE,
              options: ModelOptions = DEFAULT_OPTIONS, alpha_dot: str = "omit",
              rel_step: float = 1e-6) -> LinearModel:
    """Central-difference Jacobians of the Euler-form model about a trim (default: Table A.5's)."""
    t = trim_result if trim_result is not None else trim(params=params, options=options)
    s = t.state[0]
    x0 = np.concatenate([s[0:6], frames.euler_from_quaternion(s[QUAT]), s[10:15]])
    u0 = t.controls[0, :4].copy()
    nx, nu = x0.size, u0.size
    hx = rel_step * np.maximum(1.0, np.abs(x0))
    hu = rel_step * np.maximum(1.0, np.abs(u0))
    # all perturbations in one batched call: rows +x_i, -x_i, +u_j, -u_j
    X = np.repeat(x0[None, :], 2 * (nx + nu), axis=0)
    U = np.repeat(u0[None, :], 2 * (nx + nu), axis=0)
    for i in range(nx):
        X[2 * i, i] += hx[i]
        X[2 * i + 1, i] -= hx[i]
    for j in range(nu):
        U[2 * (nx + j), j] += hu[j]
        U[2 * (nx + j) + 1, j] -= hu[j]
    F = euler_form_derivatives(X, U, params, options, alpha_dot)
    A = ((F[0:2 * nx:2] - F[1:2 * nx:2]) / (2.0 * hx[:, None])).T
    B = ((F[2 * nx::2] - F[2 * nx + 1::2]) / (2.0 * hu[:, None])).T
    return LinearModel(A, B, x0, u0, alpha_dot=alpha_dot)


@dataclass(frozen=True)
class Mode:
    name: str
    eigenvalue: complex
    damping: float | None
    natural_frequency: float | None  # rad/s
    period: float | None  # s, oscillatory modes
    time_constant: float | None  # s, real modes (negative when unstable)

    def to_dict(self) -> dict:
        return {"name": self.name, "real": float(self.eigenvalue.real), "imag": float(abs(self.eigenvalue.imag)),
                "damping": self.damping, "natural_frequency": self.natural_frequency,
                "period": self.period, "time_constant": self.time_constant}


def _mode(name: str, lam: complex, zero_tol: float) -> Mode:
    lam = complex(lam.real, abs(lam.imag))
    wn = abs(lam)
    if abs(lam.imag) > zero_tol:
        return Mode(name, lam, float(-lam.real / wn), float(wn), float(2 * np.pi / lam.imag), None)
    if wn <= zero_tol:
        return Mode(name, lam, None, None, None, None)
    return Mode(name, lam, 1.0 if lam.real < 0 else -1.0, float(wn), None, float(-1.0 / lam.real))


def modal_analysis(A: np.ndarray, zero_tol: float = 1e-7) -> list[Mode]:
    """Eigenvalues of A as modes (one entry per real eigenvalue or complex pair), unnamed."""
    lam = np.linalg.eigvals(A)
    modes = []
    for l in sorted(lam, key=lambda z: (z.real, -z.imag)):
        if l.imag < -zero_tol:
            continue  # keep one of each conjugate pair
        modes.append(_mode("", complex(l), zero_tol))
    return modes


def _split(modes: list[Mode], zero_tol: float):
    zeros = [m for m in modes if abs(m.eigenvalue) <= zero_tol]
    osc = sorted([m for m in modes if abs(m.eigenvalue.imag) > zero_tol], key=lambda m: abs(m.eigenvalue))
    real = sorted([m for m in modes if m not in zeros and m not in osc], key=lambda m: m.eigenvalue.real)
    return zeros, osc, real


def _renamed(m: Mode, name: str) -> Mode:
    return Mode(name, m.eigenvalue, m.damping, m.natural_frequency, m.period, m.time_constant)


def name_longitudinal_modes(A_long: np.ndarray, zero_tol: float = 1e-7) -> dict[str, Mode]:
    """Name the longitudinal modes as Table A.6: surge (0, from north), short period (the faster
    pair), phugoid (the slower pair), engine (the faster real root), heave (the slower one)."""
    zeros, osc, real = _split(modal_analysis(A_long, zero_tol), zero_tol)
    named: dict[str, Mode] = {}
    for k, m in enumerate(zeros):
        named["surge" if k == 0 else f"zero_{k}"] = _renamed(m, "surge" if k == 0 else f"zero_{k}")
    if len(osc) >= 2:
        named["short_period"] = _renamed(osc[-1], "short_period")
        named["phugoid"] = _renamed(osc[0], "phugoid")
    for k, m in enumerate(osc[1:-1] if len(osc) > 2 else []):
        named[f"oscillatory_{k}"] = _renamed(m, f"oscillatory_{k}")
    if real:
        named["engine"] = _renamed(real[0], "engine")
    if len(real) >= 2:
        named["heave"] = _renamed(real[-1], "heave")
    for k, m in enumerate(real[1:-1]):
        named[f"real_{k}"] = _renamed(m, f"real_{k}")
    return named


def name_lateral_modes(A_lat: np.ndarray, zero_tol: float = 1e-7) -> dict[str, Mode]:
    """Name the lateral modes as Table A.7: sway and heading (zeros), roll subsidence (the most
    negative real root), Dutch roll (the pair), spiral (the remaining real root)."""
    zeros, osc, real = _split(modal_analysis(A_lat, zero_tol), zero_tol)
    named: dict[str, Mode] = {}
    for k, m in enumerate(zeros):
        name = ("sway", "heading")[k] if k < 2 else f"zero_{k}"
        named[name] = _renamed(m, name)
    if osc:
        named["dutch_roll"] = _renamed(osc[-1], "dutch_roll")
    for k, m in enumerate(osc[:-1]):
        named[f"oscillatory_{k}"] = _renamed(m, f"oscillatory_{k}")
    if real:
        named["roll_subsidence"] = _renamed(real[0], "roll_subsidence")
    if len(real) >= 2:
        named["spiral"] = _renamed(real[-1], "spiral")
    for k, m in enumerate(real[1:-1]):
        named[f"real_{k}"] = _renamed(m, f"real_{k}")
    return named


def open_loop_modes(trim_result: TrimResult | None = None, alpha_dot: str = "omit",
                    params: AerosondeParams = AEROSONDE, options: ModelOptions = DEFAULT_OPTIONS) -> dict:
    """Named open-loop modes ``{"longitudinal": {...}, "lateral": {...}, "model": LinearModel}``."""
    lin = linearise(trim_result, params, options, alpha_dot)
    return {
        "longitudinal": name_longitudinal_modes(lin.longitudinal().A),
        "lateral": name_lateral_modes(lin.lateral().A),
        "model": lin,
    }
