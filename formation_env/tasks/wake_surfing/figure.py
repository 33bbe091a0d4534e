"""The wake-surfing figure: the follower's saving over the safe box with the reference optimum and the paths a
policy and the extremum seeker fly (:meth:`.evaluation.WakeSurfingEvaluation.figure`)."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["plot_surfing_figure"]


def plot_surfing_figure(path, policy, seeker, fly, *, crosswind_mps: float = 4.0, seed=None, overwrite: bool = False):
    """Two panels (calm air; a steady crosswind of ``crosswind_mps``): the saving over the box at x = -2 spans, the
    reference optimum, and the paths of ``policy`` and ``seeker`` flying a demonstration episode (no turbulence, no
    manoeuvre) from the nominal slot. ``fly(policy, seeds, keep_series=, options=, overrides=)``: the driver's."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ...io import save_figure
    from ...scenarios import get_scenario
    from ...sim.config import Randomisation
    from ..base import TEST_SEED_BASE
    from .optimum import reference_optimum, saving_in_crosswind

    seed = TEST_SEED_BASE if seed is None else int(seed)
    box = np.asarray(get_scenario("wake_surfing").safe_box_b)
    y = np.linspace(box[1, 0], box[1, 1], 61)
    z = np.linspace(box[2, 0], box[2, 1], 36)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True, constrained_layout=True)
    for ax, wind in zip(axes, (0.0, crosswind_mps)):
        crab = math.asin(wind / 25.0)
        yy, zz = np.meshgrid(y, z, indexing="ij")
        grid = np.stack([np.full_like(yy, -2.0), yy, zz], axis=-1)
        sav = saving_in_crosswind(grid, crab)
        cs = ax.contourf(yy, zz, sav, levels=np.linspace(-0.1, 0.6, 29), cmap="viridis", extend="both")  # optimum 0.56
        oy, oz, osav = reference_optimum(crab)
        ax.plot(float(oy), float(oz), marker="*", ms=16, color="white", mec="k",
                label=f"reference optimum ({float(osav):.3f})")
        ax.plot(1.0, 0.3, marker="s", ms=8, color="tab:red", mec="k", label="nominal slot (thesis PID)")
        for surfer, colour, lw, label in ((seeker, "magenta", 1.0, "extremum seeking"),
                                          (policy, "tab:orange", 2.2, "PPO policy")):
            ep = fly(surfer, [seed], keep_series=True, options={"steady_wind_ned": (0.0, float(wind), 0.0)},
                     overrides={"randomisation": Randomisation()})[0]
            ax.plot(ep["series"]["lateral_b"], ep["series"]["vertical_b"], color=colour, lw=lw,
                    label=f"{label} (mean saving {ep['saving']:.3f})")
        ax.add_patch(plt.Rectangle((box[1, 0], box[2, 0]), box[1, 1] - box[1, 0], box[2, 1] - box[2, 0], fill=False,
                                   ec="k", lw=1.5, ls="--"))
        ax.set_xlim(box[1, 0] - 0.05, box[1, 1] + 0.05)
        ax.set_ylim(box[2, 1] + 0.05, box[2, 0] - 0.05)  # z down: the leader's wake plane at the top
        ax.set_xlabel("follower starboard of the leader (spans)")
        ax.set_title(f"crosswind {wind:g} m/s (crab {math.degrees(crab):.1f} deg), 2 spans behind")
        ax.legend(loc="lower right", fontsize=7)
    axes[0].set_ylabel("follower below the leader (spans)")
    fig.colorbar(cs, ax=axes, label="follower induced-drag saving")
    out = save_figure(fig, path, overwrite=overwrite, dpi=110)
    plt.close(fig)
    return out
