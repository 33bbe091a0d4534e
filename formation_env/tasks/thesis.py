"""The thesis's scenarios (chapter 6, Appendix A.5.3) and its N-UAV formations as tasks, judged against the
thesis PID and ``pid_formation`` on the generic evaluation table. Their scenarios are data in
:mod:`formation_env.scenarios.definitions`.

Benchmark configuration: set-point actions (PID tracker offsets), every episode in the frozen von Karman field at
sigma 1 m/s and each UAV starting 1 m (std, per axis) off its slot, so that no two training episodes are alike.
``formation_keeping`` adds a separation barrier of 25 from 1.5 spans (with the generic barrier, 5 from 1.2 spans,
a tailwind gust that carried the follower 10 m ahead of its slot let it pass the leader 1.4 m abeam);
``reconfiguration`` charges no forfeit of the slot cost still to come on a collision (the overtake passes 1.4
spans from the leader, and charging every collision made the policy hang back behind it)."""

from __future__ import annotations

import dataclasses

from ..sim.config import Randomisation, RewardWeights
from .base import EvaluationProtocol, RecordFile, Task, levels_record, register_task

__all__ = ["THESIS_TASKS", "THESIS_RANDOMISATION"]

#: the training randomisation of the thesis's tasks: turbulence at 1 m/s, a 1 m start jitter
THESIS_RANDOMISATION = Randomisation(turbulence_sigma_mps=1.0, initial_offset_m=1.0)
_BASE = {"action_mode": "setpoints", "randomisation": THESIS_RANDOMISATION}
_RMS = EvaluationProtocol(levels=(0.0, 1.0, 1.5), metric="rms_slot_error_m")

THESIS_TASKS = tuple(register_task(t) for t in (
    Task("formation_keeping", "formation_keeping", "formation_env/FormationKeeping", 1,
         options={**_BASE, "reward": RewardWeights(separation=25.0, barrier_separation_b=1.5)},
         description="6.5: hold the slot 2 spans behind, 1 starboard, 0.3 below",
         evaluation=dataclasses.replace(_RMS, ppo_record_score="rms_slot_error_m", records=(
             RecordFile("formation_keeping_ppo_setpoints_evaluation.json", ("policies",)),))),
    Task("reconfiguration", "reconfiguration", "formation_env/Reconfiguration", 1,
         options={**_BASE, "reward": RewardWeights(terminal_forfeit=0.0)},
         description="6.6: follow the slot schedule from behind to ahead of the leader",
         evaluation=EvaluationProtocol(levels=(0.0, 1.0, 1.5), metric="reconfig_success", absolute=True,
                                       ppo_record_score="reconfig_success", records=(
             RecordFile("reconfiguration_ppo_setpoints_evaluation.json", ("policies",)),
             levels_record("reconfiguration_algorithms_levels.json", (1.0, 0.0, 1.5))))),
    Task("gust", "gust", "formation_env/Gust", 0, options=dict(_BASE), baselines=("pid",),
         description="6.4: fly through the gusts", evaluation=_RMS),
    Task("tracking", "tracking", "formation_env/Tracking", 0, options=dict(_BASE), baselines=("pid",),
         description="A.5.3: track a displaced reference", evaluation=_RMS),
    Task("echelon", "echelon", "formation_env/Echelon", 1, options=dict(_BASE), description="right echelon of 3",
         evaluation=_RMS),
    Task("vee", "vee", "formation_env/Vee", 1, options=dict(_BASE), description="vee of 5", evaluation=_RMS),
))
