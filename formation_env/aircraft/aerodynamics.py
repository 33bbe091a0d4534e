"""Aerodynamics of the AeroSim Aerosonde: air data with clipping, coefficient build-up, forces
and moments (AeroSim Aerodynamics library; spec sections 4 to 6)."""

from __future__ import annotations

import numpy as np

from .params import AerosondeParams

__all__ = ["air_data", "aero_coefficients", "aero_forces_moments", "ZERO_OFFSET"]

ZERO_OFFSET = 1e-6  # AeroSim's "zo": a divisor below this magnitude is replaced by +-1e-6


def _zo(x: np.ndarray) -> np.ndarray:
    return np.where(np.abs(x) >= ZERO_OFFSET, x, np.where(x < 0.0, -ZERO_OFFSET, ZERO_OFFSET))


def air_data(v_rel_body: np.ndarray, params: AerosondeParams):
    """Air data from the air-relative velocity in body axes (B, 3).

    Returns ``(va_raw, alpha_raw, beta_raw, va, alpha, beta)``: the raw values and the values
    clipped to the model's bounds (the clipped ones drive everything aerodynamic; the raw
    ones only Mach and alpha-dot). alpha uses single-argument atan as AeroSim does, so it is
    confined to (-pi/2, pi/2) even in reversed flow.
    """
    ur, vr, wr = v_rel_body[..., 0], v_rel_body[..., 1], v_rel_body[..., 2]
    va_raw = np.sqrt(ur * ur + vr * vr + wr * wr)
    alpha_raw = np.arctan(wr / _zo(ur))
    beta_raw = np.arcsin(np.clip(vr / _zo(va_raw), -1.0, 1.0))
    va = np.clip(va_raw, *params.va_bounds)
    alpha = np.clip(alpha_raw, *params.alpha_bounds)
    beta = np.clip(beta_raw, *params.beta_bounds)
    return va_raw, alpha_raw, beta_raw, va, alpha, beta


def aero_coefficients(alpha, beta, va, mach, alphadot, p, q, r, flap, elevator, aileron, rudder,
                      params: AerosondeParams):
    """``(CD, CY, CL, Cl, Cm, Cn)``. Rates are the aerodynamic rates (body rates minus the
    rotational wind); ``va`` is the clipped airspeed used in the c/2V and b/2V scalings."""
    P = params
    c2v = P.mac / (2.0 * va)
    b2v = P.span / (2.0 * va)
    CL = (P.CL0 + P.CLa * alpha + P.CLdf * flap + P.CLde * elevator
          + (P.CLalphadot * alphadot + P.CLq * q) * c2v + P.CLM * mach)
    # the induced-drag term uses the complete CL (rate and control terms included), and the
    # control drag terms take the absolute value after multiplying by the derivative (AeroSim)
    CD = (P.CDmin + (CL - P.CLmind) ** 2 / (np.pi * P.osw * P.aspect_ratio)
          + np.abs(P.CDdf * flap) + np.abs(P.CDde * elevator) + np.abs(P.CDda * aileron)
          + np.abs(P.CDdr * rudder) + P.CDM * mach)
    CY = P.CYbeta * beta + P.CYda * aileron + P.CYdr * rudder + (P.CYp * p + P.CYr * r) * b2v
    Cl = P.Clbeta * beta + P.Clda * aileron + P.Cldr * rudder + (P.Clp * p + P.Clr * r) * b2v
    Cm = (P.Cm0 + P.Cma * alpha + P.Cmdf * flap + P.Cmde * elevator
          + (P.Cmalphadot * alphadot + P.Cmq * q) * c2v + P.CmM * mach)
    Cn = P.Cnbeta * beta + P.Cnda * aileron + P.Cndr * rudder + (P.Cnp * p + P.Cnr * r) * b2v
    return CD, CY, CL, Cl, Cm, Cn


def aero_forces_moments(CD, CY, CL, Cl, Cm, Cn, qbar, alpha, beta, params: AerosondeParams):
    """Aerodynamic force in body axes (B, 3) and moment about the aerodynamic centre (B, 3).

    Forces are built in wind axes ``qbar S [-CD, CY, -CL]`` and rotated to body axes with the
    clipped angles; moments are taken directly as body-axis moments (AeroSim applies no
    stability-to-body rotation to them).
    """
    qs = qbar * params.area
    fxw, fyw, fzw = -qs * CD, qs * CY, -qs * CL
    ca, sa, cb, sb = np.cos(alpha), np.sin(alpha), np.cos(beta), np.sin(beta)
    # F_body = C_wb^T F_wind with C_wb (body to wind) = [[ca cb, sb, sa cb], [-ca sb, cb, -sa sb], [-sa, 0, ca]]
    fx = ca * cb * fxw - ca * sb * fyw - sa * fzw
    fy = sb * fxw + cb * fyw
    fz = sa * cb * fxw - sa * sb * fyw + ca * fzw
    force = np.stack([fx, fy, fz], axis=-1)
    moment = np.stack([qs * params.span * Cl, qs * params.mac * Cm, qs * params.span * Cn], axis=-1)
    return force, moment
