"""Wake figures in the thesis's style: the induced-velocity field in Trefftz planes behind a wing
(Figs. 4.7/4.8) and the chapter 5.4 sweeps of the follower's effective wind (Figs. 5.6-5.10)."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np

from ..geometry import LiftingSurface, Vehicle
from ..verification.sweeps import Sweep
from ..wake import FormationState, WakeModel
from . import no_offset


def figure_4_7_wing() -> Vehicle:
    """The wing of Figs. 4.7/4.8: nseg 10, b 1 m, AR 6, taper 0.8, sweep 20 deg, dihedral 10 deg."""
    return Vehicle((LiftingSurface.from_degrees(span_m=1.0, aspect_ratio=6.0, taper=0.8, sweep_deg=20.0,
                                                dihedral_deg=10.0, nseg=10),), name="fig_4_7_wing")


def trefftz_planes_figure(x_over_b=(-1.0, -3.0, -10.0, -30.0), airspeed=20.0, alpha_deg=5.0, n=41, core="kurylowich"):
    """Induced velocity in y-z planes (body axes) behind the Fig. 4.7 wing at V 20 m/s, alpha 5 deg."""
    vehicle = figure_4_7_wing()
    b = vehicle.ref_span_m
    model = WakeModel([vehicle], core=core)
    state = FormationState.from_degrees([[0, 0, 0]], [[0, 0, 0]], airspeed, alpha_deg)
    sol = model.evaluate(state)
    fig, axes = plt.subplots(1, len(x_over_b), figsize=(4.2 * len(x_over_b), 4.0), constrained_layout=True)
    ys = np.linspace(-1.0, 1.0, n) * b
    for ax, xb in zip(np.atleast_1d(axes), x_over_b):
        x = xb * b
        zc = x * math.tan(math.radians(alpha_deg))  # behind the wing (x < 0) the legs have risen (NED z < 0)
        zs = zc + np.linspace(-0.6, 0.6, n) * b
        yy, zz = np.meshgrid(ys, zs)
        pts = np.stack([np.full(yy.size, x), yy.ravel(), zz.ravel()], -1)
        v = model.induced_velocity(state, sol, pts)[0]  # NED == body here (zero Euler angles)
        speed = np.linalg.norm(v[:, 1:], axis=1).reshape(yy.shape)
        cs = ax.contourf(yy / b, -(zz) / b, speed, levels=20, cmap="viridis")
        step = max(1, n // 16)
        ax.quiver(yy[::step, ::step] / b, -zz[::step, ::step] / b, v[:, 1].reshape(yy.shape)[::step, ::step],
                  -v[:, 2].reshape(yy.shape)[::step, ::step], color="w", scale=None)
        ax.set_title(f"x = {xb:g} b")
        ax.set_xlabel("y / b (starboard)")
        ax.set_ylabel("height / b")
        ax.set_aspect("equal")
        fig.colorbar(cs, ax=ax, shrink=0.8, label="|v_yz| (m/s)")
    fig.suptitle(f"Induced velocity in Trefftz planes behind the Fig. 4.7 wing (V {airspeed} m/s, alpha {alpha_deg} deg, {core} core)")
    return no_offset(fig)


def sweeps_figure(sweeps: list[Sweep]):
    """Follower's effective wind (body axes), rotational wind and lift increment along each sweep."""
    fig, axes = plt.subplots(3, len(sweeps), figsize=(4.5 * len(sweeps), 9.0), constrained_layout=True, squeeze=False)
    for col, sw in enumerate(sweeps):
        c = sw.coordinate
        ax = axes[0, col]
        for i, lab in enumerate(("Vi_x", "Vi_y", "Vi_z")):
            ax.plot(c, sw.wind_body[:, i], label=lab)
        ax.set_title(f"{sw.name} sweep")
        ax.set_ylabel("translational (m/s)")
        ax.legend(fontsize=8)
        ax = axes[1, col]
        for i, lab in enumerate(("omega_x", "omega_y", "omega_z")):
            ax.plot(c, sw.omega_body[:, i], label=lab)
        ax.set_ylabel("rotational (rad/s)")
        ax.legend(fontsize=8)
        ax = axes[2, col]
        ax.plot(c, sw.increments["dCL"], label="dCL (Kutta-Joukowski)")
        ax.plot(c, sw.dCL_buildup, "--", label="dCL (Eq. 5.24, no CL_q)")
        ax.set_ylabel("lift increment")
        ax.set_xlabel(f"{sw.variable} / b")
        ax.legend(fontsize=8)
        for a in axes[:, col]:
            a.grid(alpha=0.3)
    fig.suptitle("Delta wing (Table 5.5) follower in the leader's wake: effective induced wind and lift increment")
    return no_offset(fig)
