"""Task ``wake_surfing`` (issue 16): its scenario, preset, reference optimum (:mod:`.optimum`), metrics
(:mod:`.metrics`), baselines and evaluation (:mod:`.evaluation`, :mod:`.controllers`) in one unit.

Preset: the follower moves its slot set-point within the safe box
(``setpoints``: along-track fixed, lateral and vertical over the box, speed +-2 m/s) and is paid
``benefit`` per unit induced-drag saving against the same aircraft flying alone (at the same
airspeed the induced-power saving), per decision; leaving the box costs ``box`` per decision (more
than the largest artefact saving the ELL reports in the excluded band around the wake plane, so the
constraint always dominates); the slot cost and its shaping measure the along-track error only (the
along-track distance is fixed; across and vertically the follower is free within the box). Measured
with the first recipe (no slot cost, the box alone): after 400k steps the policy still drifted out of
the box along-track in every validation episode (returns flat): the box cost is flat far outside it,
and the speed set-point that holds the station needs the dense along-track signal. Each episode
draws a steady crosswind (+-5 m/s across the initial track: the crab angle turns the wake against
the track), a leader turn
(+-30 deg at 3 deg/s) and speed change (+-1 m/s) at a random time in its first half, and
turbulence at 0.25 m/s (the env's frozen von Karman field; below MIL-F-8785C's "light" at this altitude).
Measured with the thesis
PID at the nominal slot (8 training seeds): at 0.5 m/s its vertical distance to the leader wanders
with a standard deviation of 0.15-0.35 span (at 0.25 m/s 0.08-0.18). The task flies the converged wake
(issue 23 part 7): its optimum lies on the leader's wake plane (0.561 at 0.93 span starboard, z = 0.002 span in
calm air), inside the box, whose upper wall is 0.4 span above that plane. Leader climbs are left out: the wake
sheet trails along the leader's flight path, so a 1.5 m/s climb tilts it 0.12 span at the follower's distance,
and the reference optimum (a steady, level pair) would no longer be where the wake is.
"""

from __future__ import annotations

import dataclasses

from ...scenarios import Scenario, SlotSchedule, register_scenario
from ...sim.config import Randomisation, RewardWeights
from ..base import EvaluationProtocol, RecordFile, Task, register_task

__all__ = ["SCENARIO", "TASK", "WAKE_SURFING_REWARD", "WAKE_SURFING_RANDOMISATION", "BASELINES",
           "RANDOM_LEADER_SCENARIO", "RANDOM_LEADER_TASK", "RANDOM_LEADER_RANDOMISATION"]

# The follower starts in the thesis slot and may move its set-point anywhere in a safe box (0-2 spans
# starboard; vertically from 0.8 span below the leader to 0.4 span above it). Issue 23 part 7: on the converged
# wake the optimum lies on the leader's wake plane (z = 0.002 b; the saving falls by 0.22 at 0.1 b above or below
# it), and the lattice-era box (0.1-0.8 b below: a floor kept out of the nseg-10 lattice's artefact band
# |z| < 0.1 b) is gone with that artefact. The upper wall 0.4 b above the plane leaves a follower holding the
# optimum more than twice the thesis PID's vertical wander at the task's turbulence (0.08-0.18 b standard
# deviation at 0.25 m/s) before it; nothing is gained higher up (at 0.4 b above the plane the saving is 0.07).
# The along-track set-point is fixed (2 spans behind) and the slot cost holds it;
# along-track the box only keeps the follower at least 0.5 span behind the leader (and within 12): the saving
# hardly changes along the track (semi-infinite trailing legs), and the thesis PID's proportional along-track
# loop lags 8 m per 1 m/s of wind, so a tight along-track wall would be broken by the baseline itself.
# The energy-optimal position moves with the crosswind (the wake trails along the air-relative velocity) and
# with the leader's turns: .optimum.
SCENARIO = Scenario(
    "wake_surfing", "wake surfing: follower 2 spans behind the leader, starting in the thesis slot (1 span "
    "starboard, 0.3 span below), free to move within a safe box (0-2 spans starboard, 0.4 span above to 0.8 "
    "span below, behind the leader) "
    "to the position of least induced drag", duration_s=90.0,
    slots=(SlotSchedule(((0.0, (-2.0, 1.0, 0.3)),)),),
    safe_box_b=((-12.0, -0.5), (0.0, 2.0), (-0.4, 0.8)),
    # the set-point reaches 0.5 b beyond the box sideways and 1 b up and down (issue 24): with the map stopping at the
    # walls, station_keeper told the optimum (.controllers.OracleKeeper, then on the
    # lattice-era box's floor) reached 0.66 of it at sigma 0.25 (12 % of decisions outside): the thesis altitude loop
    # gives 0.03 rad of pitch per m of set-point, and a set-point held at a wall leaves it none to pull a follower back;
    # with this reach, 0.88 (0.3 % outside; 8 training-range episodes each)
    setpoint_reach_b=(0.0, 0.5, 1.0),
    # an energy task: the ELL's loads reach the 6-DOF consistently (formation_env.wake.coupling, docs/ell.md)
    wake_coupling="load_weighted",
    # the converged wake (issue 23 part 7): sheet law, span correction and the residual table of pairs
    wake_fidelity="converged")
# registered before the reference optimum is imported: the optimum reads its safe box from the registry
register_scenario(SCENARIO)
from . import evaluation as _evaluation, metrics as _metrics, optimum as _optimum  # noqa: E402

# The saving paid up to 0.8 and a box step of 4 per decision outside the box (issue 16: uncapped and 10; issue 24,
# on the lattice: a cap of 0.5 against the band where the nseg-10 lattice read up to ~1.0). On the converged wake
# nothing inside or near the box reads more than the optimum (0.561 in calm air, the same to 1e-3 under every
# crab angle), so the cap only bounds the reward; 0.8 is above the randomised-leader variant's largest optimum
# (0.729 with a 13.5 kg leader) so that it never clips what the task pays. A decision outside the box costs at
# least 4 against holding the optimum, beside the saving the metric then counts as none (the inequality
# tests/tasks/test_wake_surfing_task.py holds).
WAKE_SURFING_REWARD = RewardWeights(slot=1.0, progress=1.0, benefit=10.0, benefit_cap=0.8, box=4.0, box_scale_b=0.1,
                                    effort=0.01, rate=0.05)
# The test episodes' draws (the evaluation at the task's 0.25 m/s) ...
WAKE_SURFING_RANDOMISATION = Randomisation(turbulence_sigma_mps=0.25, crosswind_mps=5.0, leader_turn_deg=30.0,
                                           leader_speed_mps=1.0)
# ... and the training's: the turbulence intensity drawn per episode in [0, 0.5] m/s (the task's 0.25 in the middle,
# calm air and twice it at the ends) and a 1 m start jitter
WAKE_SURFING_TRAINING_RANDOMISATION = dataclasses.replace(WAKE_SURFING_RANDOMISATION, turbulence_sigma_mps=0.5,
                                                          turbulence_sigma_spread=1.0, initial_offset_m=1.0)
#: the controllers the task is judged against (its evaluation hooks build them: .evaluation, .controllers); the
#: oracle ceilings (.controllers) are reported beside them, not as baselines
BASELINES = ("pid", "pid_formation", "extremum_seeking")

_EVAL_PRESET = {"compute_benefit": True, "reward": WAKE_SURFING_REWARD, "randomisation": WAKE_SURFING_RANDOMISATION}
TASK = register_task(Task(
    "wake_surfing", SCENARIO, "formation_env/WakeSurfing", 1,
    options={"action_mode": "setpoints", "compute_benefit": True, "reward": WAKE_SURFING_REWARD,
             "randomisation": WAKE_SURFING_TRAINING_RANDOMISATION},
    evaluation=EvaluationProtocol(levels=(0.0, 0.25, 1.0), headline_level=0.25, metric="harvest_ratio",
                                  preset=_EVAL_PRESET, absolute=True, ppo_record_score="saving_ratio", records=(
                                      RecordFile("wake_surfing_ppo_setpoints_evaluation.json", ("controllers",),
                                                 (0.25,)),
                                      RecordFile("wake_surfing_ppo_setpoints_levels.json",
                                                 ("levels", "wake_surfing_sigma_{sigma}", "episodes"), (0.0, 1.0)))),
    baselines=BASELINES, reference=_optimum, metrics=_metrics.METRICS, evaluator=_evaluation.EVALUATION,
    description="move within the safe box to the position of least induced drag"))


# The randomised-leader variant (issue 24): the same scenario, preset and box, and each episode also draws the
# leader's weight (initial fuel 0.5-5 kg: 9.0-13.5 kg, AeroSim's 8.5 kg empty and 13.5 kg gross) and its speed
# (23-26 m/s from the start, plus the manoeuvre's +-1 m/s: 22-27 m/s, where the Aerosonde holds every fuel load with
# elevator and throttle to spare: 28 m/s needs full throttle, 21 m/s with 5 kg -23 deg of the 25 deg elevator). The
# crab angle, hence the optimum's position, follows the crosswind over the airspeed, and the saving there grows with
# the leader's weight (docs/wake_surfing.md, "The randomised-leader variant"): the saving to be had cannot be read off
# the measured wind alone. The draws come after all of wake_surfing's, so episode k
# of the variant has wake_surfing's episode k wind, manoeuvre and turbulence (paired).
RANDOM_LEADER_SCENARIO = dataclasses.replace(
    SCENARIO, name="wake_surfing_random_leader",
    description=SCENARIO.description + "; the leader's weight (9.0-13.5 kg) and speed (23-26 m/s) drawn per episode")
_LEADER_DRAWS = dict(leader_speed_offset_min_mps=-2.0, leader_speed_offset_max_mps=1.0, leader_fuel_offset_min_kg=-1.5,
                     leader_fuel_offset_max_kg=3.0)
RANDOM_LEADER_RANDOMISATION = dataclasses.replace(WAKE_SURFING_RANDOMISATION, **_LEADER_DRAWS)

RANDOM_LEADER_TASK = register_task(Task(
    "wake_surfing_random_leader", RANDOM_LEADER_SCENARIO, "formation_env/WakeSurfingRandomLeader", 1,
    options={**TASK.options,
             "randomisation": dataclasses.replace(WAKE_SURFING_TRAINING_RANDOMISATION, **_LEADER_DRAWS)},
    evaluation=dataclasses.replace(
        TASK.evaluation, preset={**_EVAL_PRESET, "randomisation": RANDOM_LEADER_RANDOMISATION}, absolute=False,
        ppo_record_score=None,
        # the variant's own policies, then wake_surfing's flown on the variant's episodes (per level in this order)
        records=tuple(RecordFile(f, ("levels", "wake_surfing_random_leader_sigma_{sigma}", "episodes"),
                                 (0.25, 0.0, 1.0))
                      for f in ("wake_surfing_random_leader_ppo_setpoints_levels.json",
                                "wake_surfing_ppo_setpoints_levels.json"))),
    baselines=BASELINES, reference=_optimum, metrics=_metrics.METRICS, evaluator=_evaluation.EVALUATION,
    description="wake surfing behind a leader whose weight and speed are drawn per episode: find the wake"))
