"""The close-formation saving map figure of docs/close_formation.md (the map itself:
:mod:`formation_env.tasks.close_formation.optimum`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["plot_map"]


def plot_map(path, cache: dict | None = None, *, y_b=None, z_b=None, overwrite: bool = True, **model_kw) -> Path:
    """The figure of docs/close_formation.md: saving contours over (y, z) at the cache's x with the
    optimum, its port mirror, the thesis slot and the excluded band; saving vs y at the optimum's z
    and vs z at its y. The contours use a finer grid computed here (``y_b``, ``z_b``)."""
    import matplotlib.pyplot as plt

    from ..io import save_figure
    from ..tasks.close_formation.optimum import THESIS_SLOT_B, load_cache, saving_map, slot_savings

    c = load_cache() if cache is None else cache
    x_b, z_ex = c["parameters"]["x_b"], c["z_exclusion_b"]
    opt, port = c["optimum"]["offset_b"], c["optimum_port"]["offset_b"]
    y = np.round(np.arange(-1.5, 1.5 + 1e-9, 0.02), 6) if y_b is None else np.asarray(y_b, float)
    z = np.round(np.arange(-0.5, 0.5 + 1e-9, 0.01), 6) if z_b is None else np.asarray(z_b, float)
    m = saving_map(x_b, y, z, **model_kw)
    fig = plt.figure(figsize=(9.0, 6.6))
    gs = fig.add_gridspec(2, 2, height_ratios=[1.25, 1.0])
    ax = fig.add_subplot(gs[0, :])
    levels = np.linspace(-0.6, 0.6, 25)
    cf = ax.contourf(m.y_b, m.z_b, np.clip(m.follower.T, -0.6, 0.6), levels=levels, cmap="RdBu_r", extend="both")
    in_band = np.broadcast_to(np.abs(m.z_b) < z_ex, m.follower.shape)
    outside = np.ma.masked_where(in_band, m.follower).T  # no isolines in the band
    cs = ax.contour(m.y_b, m.z_b, outside, levels=[0.15, 0.25, 0.35, 0.45], colors="k", linewidths=0.6)
    ax.clabel(cs, fmt=lambda v: f"{100 * v:.0f} %", fontsize=7)
    fig.colorbar(cf, ax=ax, label="follower induced-drag saving", ticks=np.linspace(-0.6, 0.6, 7))
    ax.axhspan(-z_ex, z_ex, facecolor="none", edgecolor="0.3", hatch="///", linewidth=0.0)
    ax.axhline(-z_ex, color="0.3", lw=0.8)
    ax.axhline(z_ex, color="0.3", lw=0.8)
    ax.plot(opt[1], opt[2], "*", ms=14, mfc="gold", mec="k", label=f"optimum ({opt[1]:.3f}, {opt[2]:.2f}) b: "
            f"{100 * c['optimum']['saving']:.1f} %")
    ax.plot(port[1], port[2], "*", ms=11, mfc="none", mec="k", label="port mirror")
    ax.plot(THESIS_SLOT_B[1], THESIS_SLOT_B[2], "X", ms=10, mfc="w", mec="k",
            label=f"thesis slot (1, 0.3) b: {100 * c['thesis_slot_saving']:.1f} %")
    if z_ex > 0:  # the nseg-10 lattice's artefact band (the converged wake has none)
        ax.plot([], [], " ", label=f"hatched: |z| < {z_ex:g} b excluded")
    ax.set_xlabel("y / b (starboard)")
    ax.set_ylabel("z / b (down)")
    ax.invert_yaxis()
    ax.set_title(f"follower at x = {x_b:g} b behind the leader (Aerosonde, ELL, trim 25 m/s)")
    ax.legend(loc="upper center", fontsize=7.5, framealpha=0.9)
    # line cuts through the optimum
    yl = np.round(np.arange(0.0, 1.5 + 1e-9, 0.005), 6)
    zl = np.round(np.arange(-0.4, 0.4 + 1e-9, 0.005), 6)
    sy = slot_savings(np.stack([np.full_like(yl, x_b), yl, np.full_like(yl, opt[2])], -1), **model_kw)[:, 1]
    s0 = slot_savings(np.stack([np.full_like(yl, x_b), yl, np.zeros_like(yl)], -1), **model_kw)[:, 1]
    sz = slot_savings(np.stack([np.full_like(zl, x_b), np.full_like(zl, opt[1]), zl], -1), **model_kw)[:, 1]
    a1 = fig.add_subplot(gs[1, 0])
    if z_ex > 0:
        a1.plot(yl, 100 * s0, color="0.65", lw=0.8, label="z = 0 (in the band)")
    a1.plot(yl, 100 * sy, "C0", label=f"z = {opt[2]:.2f} b")
    a1.axvline(opt[1], color="k", ls=":", lw=0.8)
    a1.set_ylim(-60, 110)
    a1.set_xlabel("y / b")
    a1.set_ylabel("follower saving, %")
    a1.legend(fontsize=7.5)
    a1.grid(alpha=0.3)
    a2 = fig.add_subplot(gs[1, 1])
    inb = np.abs(zl) < z_ex
    a2.plot(zl, np.where(inb, np.nan, 100 * sz), "C0", label=f"y = {opt[1]:.3f} b")
    if z_ex > 0:
        a2.plot(zl, np.where(inb, 100 * sz, np.nan), color="0.65", lw=0.8, label="excluded band")
    a2.axvspan(-z_ex, z_ex, color="0.85", zorder=0)
    a2.axvline(opt[2], color="k", ls=":", lw=0.8)
    a2.set_xlabel("z / b (down)")
    a2.legend(fontsize=7.5)
    a2.grid(alpha=0.3)
    fig.tight_layout()
    return save_figure(fig, path, overwrite=overwrite, dpi=80)

