"""Independent reference for the wake coupling: AeroSandbox's vortex-lattice method (VLM) on two Aerosonde
wings, the follower's lift, induced-drag and rolling-moment increments (formation minus the follower alone,
same attitude and air data) on the lateral and vertical sweeps of docs/ell.md ("Coupling").

Self-contained (numpy and aerosandbox only, no formation_env): run it in any environment that has
``aerosandbox`` (``pip install aerosandbox``; it is not a dependency of formation-env) to regenerate
``tests/data/coupling_aerosandbox.json``::

    python tests/oracles/aerosandbox_coupling.py [out.json]

The geometry is the ELL model's wing (formation_env.geometry.aerosonde: Table 6.1, span 2.9 m along the
dihedral line, AR 15, taper 0.4, quarter-chord sweep 4 deg, dihedral 3 deg) at the lift-matched incidence
of the ``load_weighted`` coupling (formation_env.wake.coupling.lift_matched_incidence_rad: the AeroSim
Aerosonde's CL0 / CLa); ``tests/wake/test_coupling_reference.py`` checks these numbers against the
project's. Both wings fly at the trim angle of attack at 25 m/s, 1000 m (ISA), wings level; the follower
is placed by its NED offset from the leader (x aft-negative, y starboard, z down, in spans b = 2.9 m), the
trailing vortices follow the freestream (as the ELL's legs do). Frames: AeroSandbox geometry axes are x
aft, y starboard, z up; its body axes x forward, y starboard, z down (rolling moment positive right wing
down, as the ELL's body-axis moment).
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np

SPAN_M = 2.9  # tip to tip along the dihedral line (the ELL's b)
ASPECT_RATIO = 15.0
TAPER = 0.4
SWEEP_DEG = 4.0  # quarter-chord line
DIHEDRAL_DEG = 3.0
INCIDENCE_DEG = math.degrees(0.23 / 5.6106)  # AeroSim Aerosonde CL0 / CLa (the lift-matched wing)
AIRSPEED_MPS = 25.0
ALTITUDE_M = 1000.0
ALPHA_DEG = math.degrees(0.056356858106083554)  # the 6-DOF's trim at 25 m/s, 1000 m (formation_env.aircraft.trim)
X_B = -2.0
LATERAL_Y_B = tuple(round(0.6 + 0.1 * i, 2) for i in range(9))  # 0.6 .. 1.4
LATERAL_Z_B = 0.1
VERTICAL_Y_B = 0.9
VERTICAL_Z_B = tuple(round(-0.3 + 0.1 * i, 2) for i in range(9))  # -0.3 .. 0.5
SPANWISE_RESOLUTION = 24  # panels per semispan (cosine spacing)
CHORDWISE_RESOLUTION = 4


def _wing(asb, origin_geom):
    """The ELL model's wing as an AeroSandbox Wing, its root quarter chord at ``origin_geom`` (geometry axes)."""
    area = SPAN_M**2 / ASPECT_RATIO
    c_root = 2.0 * area / (SPAN_M * (1.0 + TAPER))
    c_tip = TAPER * c_root
    half = 0.5 * SPAN_M
    tip_y = half * math.cos(math.radians(DIHEDRAL_DEG))
    tip_z = half * math.sin(math.radians(DIHEDRAL_DEG))  # up
    tip_x = tip_y * math.tan(math.radians(SWEEP_DEG))  # quarter chord, aft
    ox, oy, oz = origin_geom
    foil = asb.Airfoil("naca0012")  # symmetric: no camber, the flat lifting surface of the ELL
    # port tip, root, starboard tip (not ``symmetric=True``: AeroSandbox mirrors about its own y = 0 plane,
    # which would put the follower's mirror half on the far side of the leader)
    xsecs = [asb.WingXSec(xyz_le=[ox + tip_x - 0.25 * c_tip, oy + side * tip_y, oz + tip_z], chord=c_tip,
                          twist=INCIDENCE_DEG, airfoil=foil) if side else
             asb.WingXSec(xyz_le=[ox - 0.25 * c_root, oy, oz], chord=c_root, twist=INCIDENCE_DEG, airfoil=foil)
             for side in (-1, 0, 1)]
    return asb.Wing(name="wing", xsecs=xsecs, symmetric=False)


def _offset_geom(x_b, y_b, z_b):
    """The follower's root quarter chord in the leader's geometry axes, from its NED offset (spans); both
    aircraft pitched by theta = alpha (level flight)."""
    th = math.radians(ALPHA_DEG)
    xn, yn, zn = x_b * SPAN_M, y_b * SPAN_M, z_b * SPAN_M
    xb = math.cos(th) * xn - math.sin(th) * zn
    zb = math.sin(th) * xn + math.cos(th) * zn
    return (-xb, yn, -zb)


def follower_increments(y_b, z_b, x_b=X_B, spanwise=SPANWISE_RESOLUTION, chordwise=CHORDWISE_RESOLUTION):
    """The follower's lift (N), induced drag (N) and rolling moment (N m, about its root quarter chord,
    body axes) in formation and alone, and their increments."""
    import aerosandbox as asb

    op = asb.OperatingPoint(atmosphere=asb.Atmosphere(altitude=ALTITUDE_M), velocity=AIRSPEED_MPS, alpha=ALPHA_DEG,
                            beta=0.0)
    off = _offset_geom(x_b, y_b, z_b)
    follower = _wing(asb, off)

    def run(wings):
        plane = asb.Airplane(wings=wings, xyz_ref=list(off), s_ref=SPAN_M**2 / ASPECT_RATIO, b_ref=SPAN_M,
                             c_ref=SPAN_M / ASPECT_RATIO)
        vlm = asb.VortexLatticeMethod(plane, op, xyz_ref=list(off), spanwise_resolution=spanwise,
                                      chordwise_resolution=chordwise, align_trailing_vortices_with_wind=True)
        vlm.run()
        n_f = len(vlm.vortex_strengths) if len(wings) == 1 else len(vlm.vortex_strengths) // 2
        # the follower's panels only (in formation the leader's come first)
        sl = slice(len(vlm.vortex_strengths) - n_f, None)
        f_g = np.sum(vlm.forces_geometry[sl], axis=0)
        m_g = np.sum(vlm.moments_geometry[sl], axis=0)
        f_b = np.array(op.convert_axes(*f_g, from_axes="geometry", to_axes="body"))
        f_w = np.array(op.convert_axes(*f_b, from_axes="body", to_axes="wind"))
        m_b = np.array(op.convert_axes(*m_g, from_axes="geometry", to_axes="body"))
        return float(-f_w[2]), float(-f_w[0]), float(m_b[0])

    l_f, d_f, r_f = run([_wing(asb, (0.0, 0.0, 0.0)), follower])
    l_a, d_a, r_a = run([follower])
    return {"lift_n": l_f, "drag_n": d_f, "roll_nm": r_f, "lift_alone_n": l_a, "drag_alone_n": d_a,
            "roll_alone_nm": r_a, "dlift_n": l_f - l_a, "ddrag_n": d_f - d_a, "droll_nm": r_f - r_a}


def table() -> dict:
    """Both sweeps and the set-up, as written to the data file."""
    import aerosandbox as asb

    rows = []
    for y in LATERAL_Y_B:
        rows.append({"sweep": "lateral", "x_b": X_B, "y_b": y, "z_b": LATERAL_Z_B,
                     **follower_increments(y, LATERAL_Z_B)})
    for z in VERTICAL_Z_B:
        rows.append({"sweep": "vertical", "x_b": X_B, "y_b": VERTICAL_Y_B, "z_b": z,
                     **follower_increments(VERTICAL_Y_B, z)})
    return {
        "source": "tests/oracles/aerosandbox_coupling.py", "aerosandbox_version": asb.__version__,
        "geometry": {"span_m": SPAN_M, "aspect_ratio": ASPECT_RATIO, "taper": TAPER, "sweep_deg": SWEEP_DEG,
                     "dihedral_deg": DIHEDRAL_DEG, "incidence_deg": INCIDENCE_DEG},
        "operating_point": {"airspeed_mps": AIRSPEED_MPS, "altitude_m": ALTITUDE_M, "alpha_deg": ALPHA_DEG,
                            "density_kg_m3": float(asb.Atmosphere(altitude=ALTITUDE_M).density())},
        "lattice": {"spanwise_per_semispan": SPANWISE_RESOLUTION, "chordwise": CHORDWISE_RESOLUTION,
                    "spacing": "cosine", "vortex_core_radius_m": 1e-8, "trailing_vortices": "along the freestream"},
        "rows": rows,
    }


if __name__ == "__main__":
    default = Path(__file__).resolve().parents[1] / "data" / "coupling_aerosandbox.json"
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else default
    out.write_text(json.dumps(table(), indent=1) + "\n")
    print(f"wrote {out}")
