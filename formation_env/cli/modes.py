"""``formation-env modes``: eigenvalues, damping and frequency of the Aerosonde's modes.

The mode set is chosen by a *source*: ``open_loop`` (default) or ``closed_loop``
(``--closed-loop``: the Appendix A FCS of :mod:`formation_env.control` closed around the aircraft, with each
pole set beside Tables A.11/A.12).
"""

from __future__ import annotations

from ._args import finite_float

import json
from typing import Callable



def _open_loop(args) -> dict:
    from ..aircraft.linearise import open_loop_modes
    from ..aircraft.trim import trim

    t = trim(args.speed, args.altitude, args.fuel)
    m = open_loop_modes(t, alpha_dot="include" if args.alpha_dot else "omit")
    return {
        "source": "open_loop",
        "trim": {"airspeed": t.airspeed, "altitude": t.altitude, "fuel": t.fuel},
        "alpha_dot": "include" if args.alpha_dot else "omit",
        "longitudinal": {k: v.to_dict() for k, v in m["longitudinal"].items()},
        "lateral": {k: v.to_dict() for k, v in m["lateral"].items()},
    }


def _closed_loop(args) -> dict:
    from ..aircraft.trim import trim
    from ..control.closed_loop import closed_loop_table

    t = trim(args.speed, args.altitude, args.fuel)
    table = closed_loop_table(t, alpha_dot="include" if args.alpha_dot else "omit")
    return {"source": "closed_loop", "trim": {"airspeed": t.airspeed, "altitude": t.altitude, "fuel": t.fuel},
            **table}


# name -> function(args) returning {"longitudinal": {name: mode dict}, "lateral": {...}, ...}
SOURCES: dict[str, Callable] = {"open_loop": _open_loop, "closed_loop": _closed_loop}


def register(sub) -> None:
    p = sub.add_parser("modes", help="open-loop (Tables A.6/A.7) or closed-loop (A.11/A.12) modes about the trim")
    p.add_argument("--speed", type=finite_float, default=25.0, help="trim airspeed, m/s (default 25)")
    p.add_argument("--altitude", type=finite_float, default=1000.0, help="trim altitude, m (default 1000)")
    p.add_argument("--fuel", type=finite_float, default=2.0, help="fuel, kg (default 2)")
    p.add_argument("--alpha-dot", action="store_true",
                   help="include the alpha-dot terms (the thesis tables omit them, as Simulink linmod does)")
    p.add_argument("--closed-loop", dest="source", action="store_const", const="closed_loop", default="open_loop",
                   help="modes with the Appendix A FCS closed around the aircraft (Tables A.11/A.12)")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=run)


def _fmt(x, spec=".4g") -> str:
    return "-" if x is None else format(x, spec)


def run(args) -> int:
    source = getattr(args, "source", "open_loop")
    if source not in SOURCES:
        raise ValueError(f"unknown mode source {source!r}; available: {sorted(SOURCES)}")
    result = SOURCES[source](args)
    if args.json:
        print(json.dumps(result, indent=2))
        return 0
    print(f"{result['source']} modes, alpha-dot {result.get('alpha_dot', '-')}, trim {result.get('trim', {})}")
    for group in ("longitudinal", "lateral"):
        print(f"  {group}:")
        print(f"    {'mode':<18s} {'eigenvalue':>24s} {'damping':>9s} {'wn rad/s':>9s} {'period s':>9s}")
        for name, m in result[group].items():
            if "thesis" in m:
                name = f"{name} (thesis {m['thesis'][0]:.3g}{' +- %.3gi' % m['thesis'][1] if m['thesis'][1] else ''})"
            lam = f"{m['real']:.4g}" + (f" +- {m['imag']:.4g}i" if m["imag"] > 0 else "")
            print(f"    {name:<18s} {lam:>24s} {_fmt(m['damping'], '.3f'):>9s} "
                  f"{_fmt(m['natural_frequency']):>9s} {_fmt(m.get('period')):>9s}")
    return 0


__all__ = ["SOURCES", "register", "run"]
