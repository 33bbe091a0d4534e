"""Aerosonde verification sections for ``formation-env verify``: the Table A.5 trim (``trim_a5``)
and the open-loop modes of Tables A.6/A.7 (``modes_open``) and the closed-loop modes of Tables
A.11/A.12 (``modes_closed``), computed beside the thesis values."""

from __future__ import annotations

from ..aircraft.linearise import open_loop_modes
from ..aircraft.trim import trim
from .thesis_values import thesis_values

__all__ = ["SECTIONS", "trim_a5", "modes_open", "modes_closed"]

# Issue 3 acceptance tolerances.
_TRIM_TOL = {"alpha_rad": 5e-4, "theta_rad": 5e-4, "elevator_rad": 1e-3, "aileron_rad": 5e-4,
             "rudder_rad": 3e-4, "throttle": 5e-3, "engine_speed_rad_s": 2.0}
_MODE_REL_TOL = 0.10


def _entry(computed: float, thesis: float, tol: float, note: str | None = None) -> dict:
    err = abs(computed - thesis)
    d = {"computed": float(computed), "thesis": float(thesis), "tolerance": tol,
         "max_abs_error": float(err), "ok": bool(err <= tol)}
    if note:
        d["note"] = note
    return d


def trim_a5() -> dict:
    """Straight and level trim at 25 m/s, 1000 m, 2 kg fuel against Table A.5."""
    ref = thesis_values()["table_a5_trim"]
    t = trim(ref["V_mps"], ref["altitude_m"], ref["fuel_kg"])
    out = {
        "alpha_rad": _entry(t.alpha, ref["alpha_rad"], _TRIM_TOL["alpha_rad"]),
        "theta_rad": _entry(t.theta, ref["theta_rad"], _TRIM_TOL["theta_rad"]),
        "elevator_rad": _entry(t.elevator, ref["elevator_rad"], _TRIM_TOL["elevator_rad"]),
        "aileron_rad": _entry(t.aileron, ref["aileron_rad"], _TRIM_TOL["aileron_rad"]),
        "rudder_rad": _entry(t.rudder, ref["rudder_rad"], _TRIM_TOL["rudder_rad"]),
        "throttle": _entry(t.throttle, 10.0 * ref["throttle"], _TRIM_TOL["throttle"],
                           note="thesis prints 0.07063, a one-decimal slip for 0.7063"),
        "engine_speed_rad_s": _entry(t.omega, ref["engine_speed_rad_s"], _TRIM_TOL["engine_speed_rad_s"]),
        "u_mps": _entry(t.state[0, 0], ref["u_mps"], 1e-3),
        "v_mps": _entry(t.state[0, 1], ref["v_mps"], 1e-4),
        "w_mps": _entry(t.state[0, 2], ref["w_mps"], 2e-4),
        "beta_rad": _entry(t.beta, ref["beta_rad"], 1e-4),
        "psi_rad": _entry(t.psi, ref["psi_rad"], 1e-4),
    }
    out["ok"] = all(v["ok"] for v in out.values())
    out["details"] = {k: float(v) for k, v in t.extras.items()}
    return out


def _mode_entry(lam: complex, ref: complex) -> dict:
    err = abs(lam - ref)
    return {"computed": [lam.real, abs(lam.imag)], "thesis": [ref.real, abs(ref.imag)],
            "relative_error": float(err / abs(ref)), "tolerance": f"{_MODE_REL_TOL:.0%} of |lambda|",
            "max_abs_error": float(err), "ok": bool(err <= _MODE_REL_TOL * abs(ref))}


def modes_open() -> dict:
    """Open-loop modes about the Table A.5 trim (alpha-dot terms omitted, as linmod) against
    Tables A.6/A.7; the short period with alpha-dot included is reported beside them."""
    tv = thesis_values()
    a6, a7 = tv["table_a6_open_loop_longitudinal"], tv["table_a7_open_loop_lateral"]
    t = trim()
    m = open_loop_modes(t, alpha_dot="omit")
    lon, lat = m["longitudinal"], m["lateral"]
    refs = {
        "short_period": (lon, complex(*a6["sppo"])),
        "engine": (lon, complex(a6["engine"])),
        "phugoid": (lon, complex(*a6["phugoid"])),
        "heave": (lon, complex(a6["heave"])),
        "roll_subsidence": (lat, complex(a7["roll_subsidence"])),
        "dutch_roll": (lat, complex(*a7["dutch_roll"])),
        "spiral": (lat, complex(a7["spiral"])),
    }
    out = {name: _mode_entry(group[name].eigenvalue, ref) for name, (group, ref) in refs.items()}
    out["ok"] = all(v["ok"] for v in out.values())
    full = open_loop_modes(t, alpha_dot="include")
    sp = full["longitudinal"]["short_period"].eigenvalue
    out["with_alpha_dot"] = {
        "short_period": [sp.real, abs(sp.imag)],
        "note": "alpha-dot terms included (physically complete); the thesis tables match the "
                "alpha-dot-free linearisation, as Simulink linmod gives with AeroSim's Derivative block",
    }
    return out


def modes_closed() -> dict:
    """Closed-loop modes (the Appendix A FCS of :mod:`formation_env.control` around the Table A.5 trim,
    alpha-dot terms omitted) against Tables A.11/A.12, 15 % of |lambda| per pole."""
    from ..control.closed_loop import closed_loop_table

    return closed_loop_table(trim())


SECTIONS = {"trim_a5": trim_a5, "modes_open": modes_open, "modes_closed": modes_closed}
