"""``formation-env trim``: trim the Aerosonde (straight and level, climb, or coordinated turn)."""

from __future__ import annotations

from ._args import finite_float

import json

import numpy as np


def register(sub) -> None:
    p = sub.add_parser("trim", help="trim the Aerosonde 6-DOF model (thesis Table A.5 by default)")
    p.add_argument("--speed", type=finite_float, default=25.0, help="airspeed, m/s (default 25)")
    p.add_argument("--altitude", type=finite_float, default=1000.0, help="altitude, m (default 1000)")
    p.add_argument("--fuel", type=finite_float, default=2.0, help="fuel on board, kg (default 2)")
    p.add_argument("--climb-angle", type=finite_float, default=0.0, metavar="DEG",
                   help="flight-path angle, deg, + climbing (default 0)")
    p.add_argument("--turn-rate", type=finite_float, default=0.0, metavar="DEG_S",
                   help="turn rate, deg/s, + right (default 0)")
    p.add_argument("--gravity", choices=("constant", "wgs84"), default="constant",
                   help="gravity model: constant 9.81 (reproduces the thesis) or WGS-84 at 45N")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..aircraft.eom import ModelOptions
    from ..aircraft.trim import trim

    t = trim(args.speed, args.altitude, args.fuel, flight_path_angle=np.deg2rad(args.climb_angle),
             turn_rate=np.deg2rad(args.turn_rate), options=ModelOptions(gravity_model=args.gravity))
    d = t.to_dict()
    if args.json:
        d["state"] = t.state[0].tolist()
        d["controls"] = t.controls[0].tolist()
        print(json.dumps(d, indent=2))
        return 0
    print(f"Aerosonde trim: V = {t.airspeed:g} m/s, h = {t.altitude:g} m, fuel = {t.fuel:g} kg, "
          f"gamma = {np.rad2deg(t.flight_path_angle):g} deg, turn rate = {np.rad2deg(t.turn_rate):g} deg/s")
    rows = [
        ("alpha", t.alpha, "rad"), ("beta", t.beta, "rad"), ("phi", t.phi, "rad"), ("theta", t.theta, "rad"),
        ("psi", t.psi, "rad"), ("u", d["u"], "m/s"), ("v", d["v"], "m/s"), ("w", d["w"], "m/s"),
        ("elevator", t.elevator, "rad"), ("aileron", t.aileron, "rad"), ("rudder", t.rudder, "rad"),
        ("throttle", t.throttle, "-"), ("shaft speed", t.omega, "rad/s"),
        ("MAP", d["map_kpa"], "kPa"), ("shaft power", d["power"], "W"), ("thrust", d["thrust"], "N"),
        ("fuel flow", d["fuel_flow_g_per_h"], "g/h"), ("max |residual|", t.residual_norm, ""),
    ]
    for name, val, unit in rows:
        print(f"  {name:<15s} {val: .6g} {unit}")
    return 0
