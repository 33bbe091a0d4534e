"""The wake-surfing task's per-episode metrics, recorded on the batched rollout (:func:`formation_env.rollout.rollout`)
and measured against each episode's reference optimum (:mod:`.optimum`).

Per episode (10 Hz decisions, the follower):

=========================  =========================================================================
saving                     mean induced-drag saving over the episode (1 - D_i formation / D_i alone),
                           a decision outside the safe box counted as 0 (there the saving may be the
                           ELL's wake-plane artefact); ``saving_measured``: every decision as measured
reference_saving           mean over the episode of the reference optimum's saving at each instant's
                           crab angle (:func:`.optimum.episode_reference`: from the steady wind, the leader's
                           demanded track and its air speed |v_demand - wind|); with the leader's weight and
                           speed drawn (the randomised-leader variant), times :func:`.optimum.leader_factor` at
                           the episode's mean crab and air speed and the two aircraft's fuel at the start
leader_mass_kg             the leader's mass at the start; ``leader_airspeed_mps``: its demanded air speed,
                           mean over the episode
saving_ratio               saving / reference_saving
time_to_80_s               first time the saving (counted as above), averaged over the last second,
                           reaches 80 % of the reference (NaN: never)
drag_saving_pct_ell        the energy account (:mod:`formation_env.sim.energy`), mean over the decisions: the
                           ELL's predicted reduction of the follower's total drag at the flown state, % of its
                           drag alone (an ended episode's missing decisions count as 0)
drag_saving_pct_6dof       the reduction of the drag along the flight path the 6-DOF applies, formation against
                           the same state and controls without the wake, %
box_outside_frac           fraction of the decisions outside the safe box
box_outside_longest_s      longest continuous time outside the box
min_separation_m           smallest CG distance to the leader at the decision instants
collision / crashed        the episode ended by a collision / an envelope exit; an episode that ended early
                           counts the decisions it did not fly as outside the box with no saving
lateral_b, vertical_b      the follower's path relative to the leader (track frame, spans), and the
                           reference optimum's, for the figure (with ``keep_series``)
=========================  =========================================================================
"""

from __future__ import annotations

import numpy as np

from ...aircraft import AEROSONDE
from ...aircraft.mass import mass_properties
from ...frames import ned_to_track_frame
from ...rollout import Recorder, RolloutResult
from ...scenarios import AEROSONDE_SPAN_M
from ...sim.energy import ENERGY_COLUMNS
from ..evaluation import longest_run

__all__ = ["WakeSurfingRecorder", "WakeSurfingMetrics", "METRICS", "episode_metrics", "longest_run", "WINDOW_S"]

WINDOW_S = 1.0  # the saving is averaged over this before the 80 % test


class WakeSurfingRecorder(Recorder):
    """Records the follower (vehicle 1) of every formation at each decision (NaN once its episode ended)."""

    def start(self, sim, out) -> None:
        self.rec = {k: [] for k in ("saving", "box", "sep", "rel", "chi", "speed", "ell", "sixdof")}
        self.wind = sim.state.steady_wind.copy()  # each episode's steady wind (the reference follows it)
        # the leader's and the follower's fuel at the start (a drawn leader weight scales the saving: optimum.leader_factor)
        self.fuel = sim.state.aircraft[:, :2, 13].copy()
        self.mass = mass_properties(self.fuel, AEROSONDE)[0]
        self.random_leader = sim.config.randomisation.random_leader
        self.hz = sim.config.control_hz
        self.full_decisions = -(-sim.n_steps // sim.substeps)  # an episode flown to the end

    def after_step(self, sim, out, actions, alive, k) -> None:
        rec, info = self.rec, out.info
        saving = np.where(alive, info.induced_drag_saving[:, 1], 0.0)
        vd0 = sim.velocity_demand[:, 0]
        chi = np.arctan2(vd0[:, 1], vd0[:, 0])
        rel = ned_to_track_frame(sim.aircraft[:, 1, 10:13] - sim.aircraft[:, 0, 10:13], chi) / AEROSONDE_SPAN_M
        rec["saving"].append(np.where(alive, saving, np.nan))
        rec["box"].append(np.where(alive, info.box_depth_m[:, 1], np.nan))
        rec["sep"].append(np.where(alive, sim.output.separation_m[:, 1], np.nan))
        rec["rel"].append(np.where(alive[:, None], rel, np.nan))
        rec["chi"].append(chi)
        rec["speed"].append(np.linalg.norm(vd0 - self.wind, axis=1))  # the demanded air speed
        acc = info.energy_account[:, 1]  # the follower's energy account (zeros without wake)
        rec["ell"].append(np.where(alive, acc[:, ENERGY_COLUMNS.index("drag_saving_pct_ell")], np.nan))
        rec["sixdof"].append(np.where(alive, acc[:, ENERGY_COLUMNS.index("drag_saving_pct_6dof")], np.nan))


def episode_metrics(rec: WakeSurfingRecorder, result: RolloutResult, keep_series: bool = False) -> list[dict]:
    """The module's table for every episode of a rollout recorded by ``rec``."""
    from .optimum import episode_reference

    hz, wind = rec.hz, rec.wind
    arr = {key: np.stack(v) for key, v in rec.rec.items()}  # (T, B, ...)
    window = max(1, int(round(WINDOW_S * hz)))
    out = []
    for i, seed in enumerate(result.seeds):
        n = int(result.decisions[i])
        # an episode that ended early (collision, envelope) is scored as a failure for the time it did not fly:
        # no saving there, and outside the box
        missing = rec.full_decisions - n if result.terminated[i] else 0
        sv = arr["saving"][:n, i]
        outside = np.concatenate([arr["box"][:n, i] > 0.0, np.ones(missing, bool)])
        # outside the box a decision earns nothing: the box is the task's constraint (on the nseg-10 lattice the
        # saving there could be the wake-plane band's artefact; on the converged wake the port side of the wake lies
        # beyond the port wall under a strong crab)
        sv_in = np.where(outside, 0.0, np.concatenate([sv, np.zeros(missing)]))
        fuel = dict(leader_fuel_kg=float(rec.fuel[i, 0]), follower_fuel_kg=float(rec.fuel[i, 1])) \
            if rec.random_leader else {}
        ref = episode_reference(wind[i], arr["chi"][:n, i], arr["speed"][:n, i], **fuel)
        ref_saving = float(ref["mean_saving"])
        smooth = np.convolve(sv_in[:n], np.ones(window) / window, mode="full")[:n]
        smooth[:window - 1] = -np.inf  # a full second first
        reached = np.nonzero(smooth >= 0.8 * np.asarray(ref["saving"]))[0]
        m = {
            "seed": seed,
            "duration_s": n / hz,
            "saving": float(np.mean(sv_in)),
            "saving_measured": float(np.mean(sv)),
            "reference_saving": ref_saving,
            "saving_ratio": float(np.mean(sv_in) / ref_saving),
            "time_to_80_s": float((reached[0] + 1) / hz) if len(reached) else float("nan"),
            "drag_saving_pct_ell": float(np.sum(arr["ell"][:n, i]) / (n + missing)),
            "drag_saving_pct_6dof": float(np.sum(arr["sixdof"][:n, i]) / (n + missing)),
            "box_outside_frac": float(np.mean(outside)),
            "box_outside_longest_s": float(longest_run(outside) / hz),
            "min_separation_m": float(np.nanmin(arr["sep"][:n, i])),
            "collision": bool(result.collided[i]),
            "crashed": bool(result.crashed[i]),
            "crosswind_mps": float(wind[i, 1]),
            "leader_mass_kg": float(rec.mass[i, 0]),
            "leader_airspeed_mps": float(np.mean(arr["speed"][:n, i])),
            "reference_factor": float(ref["factor"]),
        }
        if keep_series:
            m["series"] = {"lateral_b": arr["rel"][:n, i, 1].tolist(), "vertical_b": arr["rel"][:n, i, 2].tolist(),
                           "saving": sv.tolist(), "reference_lateral_b": np.asarray(ref["y_b"]).tolist(),
                           "reference_vertical_b": np.asarray(ref["z_b"]).tolist()}
        out.append(m)
    return out


class WakeSurfingMetrics:
    """The task's metrics as :attr:`formation_env.tasks.Task.metrics` holds them: ``recorder()``, then
    ``episodes(recorder, result)`` (:func:`episode_metrics`)."""

    def recorder(self) -> WakeSurfingRecorder:
        return WakeSurfingRecorder()

    def episodes(self, recorder: WakeSurfingRecorder, result: RolloutResult, keep_series: bool = False) -> list[dict]:
        return episode_metrics(recorder, result, keep_series=keep_series)

    def __repr__(self) -> str:
        return "WakeSurfingMetrics()"


METRICS = WakeSurfingMetrics()
