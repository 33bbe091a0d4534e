"""Task ``vee_rotation``: the leader of a vee of 5 hands over the lead and drops back to a trailing slot, as
geese rotate the lead (issue 25).

The formation starts and ends as ``vee5``'s joint induced-drag optimum (:mod:`.optimum`): apex vehicle 0,
rank 1 at s1 = (-2, +-0.89, 0) b, rank 2 at s2 = (-4, +-1.79, 0) b (x forward, y starboard, z down, from the
UAV at the apex). After the rotation the starboard rank-1 follower (vehicle 1) is the apex, vehicle 3 its
starboard rank 1, vehicle 0 its starboard rank 2 (the tired leader at the end of a side), vehicles 2 and 4 keep
their port slots. Slots are relative to vehicle 0 (as an agent, below), so in its frame the rotation is the four
followers moving forward and to port, past it. Over the ground it is the leader that drops back, as geese do: its
reference (:func:`leader_dropback_keyframes`) slows so that vehicle 1 holds its place, and it is carried by the air
along the track and vertically (``Scenario.leader_air_relative``: a leader holding its airspeed and flying level in
the air mass). Posed with a leader that held 25 m/s over the ground at a fixed altitude, the rotation in turbulence
was thrust-limited: a sustained downdraft took the leader's whole throttle (55 m behind its reference in one episode)
and the followers could not gain on a leader at full throttle (docs/multi_agent.md). In vehicle 0's frame: with
A = -s2 the new apex relative to vehicle 0, vehicle 1 ends at A, vehicle 3 at A + s1, vehicle 2 at A + mirror(s1) and vehicle 4 at A +
mirror(s2). The schedule (:func:`rotation_keyframes`) orders the moves so that no two paths cross and every
pass is abeam at least two lateral steps (~1.8 b, 5 m against the 1.45 m collision separation):

1. hold the vee (settle);
2. the port side steps out to port by the rank-2 lateral offset (it makes room for the starboard side), the
   starboard side out to starboard by one rank-1 lateral step (its passing margin);
3. every follower moves forward by -2 s2_x (6 b for rank 1 starboard, 4 b for the others) on its own line,
   and to its final height (the new vee's; at the converged optimum every rank flies its wake plane, one height);
4. the starboard side, now ahead of vehicle 0, shifts to port onto its final slots (vehicle 3 crosses
   vehicle 0's line two spans ahead of it, vehicle 1 four);
5. hold (the success window: every follower within 1 span of its final slot for the last 5 s, no collision).

Every UAV is an agent, vehicle 0 included (its slot is its own track): after the rotation it flies in the wake
of the new vee, where the thesis PID is not fit to fly it. Judged by the success rate, collisions and
separation; baselines the thesis PID and ``station_keeper`` on every UAV (they track the moving slots through
the schedule's offset and rate).
"""

from __future__ import annotations

import numpy as np

from ...scenarios import Scenario, SlotSchedule
from ...sim.config import RewardWeights
from ..base import EvaluationProtocol, Task, levels_record, register_task
from . import optimum as _optimum

__all__ = ["PHASES_S", "rotation_keyframes", "leader_dropback_keyframes", "SCENARIO", "ROTATION_REWARD", "register"]

#: phase boundaries, s: hold to 15, port side out 15-25, forward 25-50, starboard side to port 50-62, hold to 80
PHASES_S = (15.0, 25.0, 50.0, 62.0, 80.0)


def rotation_keyframes(slots_b, phases_s=PHASES_S) -> tuple:
    """The four followers' keyframes ``((t, (x, y, z)), ...)`` in spans from vehicle 0 for the vee whose
    follower slots are ``slots_b`` (4 x 3: starboard rank 1, port rank 1, starboard rank 2, port rank 2, as
    ``vee5``'s) and the phase boundaries ``phases_s`` (5 increasing times: end of the first hold, of the port
    step, of the forward move, of the starboard shift, and the episode's end)."""
    s = np.asarray(slots_b, float).reshape(4, 3)
    times = tuple(float(t) for t in phases_s)
    if len(times) != 5 or not 0.0 < times[0] < times[1] < times[2] < times[3] < times[4]:
        raise ValueError(f"rotation_keyframes: phases_s must be 5 increasing positive times, got {phases_s!r}")
    t_hold, t_out, t_fwd, t_shift, _ = times
    apex = -s[2]  # the new apex (vehicle 1) relative to vehicle 0, which ends at its starboard rank 2
    final = np.array([apex, apex + s[1], apex + s[0], apex + s[3]])  # vehicles 1, 2, 3, 4
    out = []
    for j in range(4):
        start, end = s[j], final[j]
        starboard = j in (0, 2)
        # 2: the port side steps out to its final line (by the rank-2 lateral offset); the starboard side out
        # by one rank-1 lateral step, so that it passes vehicle 0 abeam at two steps (~5 m), not one
        p2 = start.copy()
        p2[1] = start[1] + s[0, 1] if starboard else end[1]
        # 3: forward to the final x and height, on its line (the starboard side keeps its y until it is ahead)
        p3 = np.array([end[0], p2[1], end[2]])
        # 4: the starboard side shifts to port, ahead of vehicle 0
        p4 = end.copy()
        kf = ((0.0, start), (t_hold, start), (t_out, p2), (t_fwd, p3), (t_shift, p4))
        out.append(tuple((t, tuple(float(round(v, 6)) for v in p)) for t, p in kf))
    return tuple(out)


def leader_dropback_keyframes(keyframes) -> tuple:
    """Vehicle 0's own keyframes ``((t, (x, 0, z)), ...)`` in spans from the reference for the followers'
    ``keyframes`` (:func:`rotation_keyframes`): the leader drops back and down exactly as far as vehicle 1 (the new
    apex) moves up relative to it, on the same blends, so that vehicle 1 holds its place along the track and its
    height while vehicles 0, 2 and 4 slow down and vehicle 3 holds its speed. No UAV is asked to fly faster than the
    reference (25 m/s) at any time: the hand-over costs throttle, not thrust (measured: posed as the others
    outrunning the leader, the rotation in turbulence was limited by the Aerosonde's thrust; docs/multi_agent.md)."""
    kf1 = keyframes[0]
    x0, z0 = kf1[0][1][0], kf1[0][1][2]
    return tuple((t, (float(round(-(off[0] - x0), 6)) + 0.0, 0.0, float(round(-(off[2] - z0), 6)) + 0.0))
                 for t, off in kf1)


def _scenario() -> Scenario:
    entry = _optimum.optimum("vee5")
    keyframes = rotation_keyframes(entry["slots_b"])
    return Scenario("vee_rotation", "vee of 5 rotating the lead: vehicle 0 hands the apex to vehicle 1 and drops back "
                    "to the starboard rank 2 while the others move up (port side out, all forward 4-6 spans, the "
                    "starboard side across ahead of vehicle 0), then holds the new vee",
                    duration_s=PHASES_S[-1], slots=tuple(SlotSchedule(kf) for kf in keyframes),
                    leader_schedule=SlotSchedule(leader_dropback_keyframes(keyframes)), leader_air_relative=True,
                    notes={"phases_s": list(PHASES_S), "start_and_end": "vee5's joint optimum, apex vehicle 0 -> 1"},
                    wake_coupling="load_weighted", wake_fidelity="converged", neighbour_count=2)


SCENARIO = _scenario()
# every UAV an agent, vehicle 0 included: after the rotation it flies in the new vee's wake (at the end of the
# starboard side), and the thesis PID there swings +-3 m laterally in calm air (measured, seed 1), which the
# followers' slots (relative to vehicle 0's track) then carry into a collision; its slot is its own track
# The benchmark: vee5's, with the along-track error counted fully (the success window is a 3-D distance, 1 span for the
# last 5 s, where the vee5 policies hold the along-track error loosely and miss it by 2-3 m) and a hold term charging
# each decision of the hold phase outside 0.75 span; the saving paid 2 per unit
ROTATION_REWARD = RewardWeights(slot_scale_m=0.29, along_track_weight=1.0, benefit=2.0, benefit_cap=0.66,
                                separation=25.0, barrier_separation_b=1.5, hold=1.0, hold_radius_b=0.75)


def register(base_options: dict) -> Task:
    """Registers ``vee_rotation``: the N-UAV formations' options ``base_options`` with :data:`ROTATION_REWARD`.
    The package calls it with its options (it owns them; this module does not import the package)."""
    return register_task(Task("vee_rotation", SCENARIO, "formation_env/VeeRotation", 1,
                              options={**base_options, "reward": ROTATION_REWARD},
                              evaluation=EvaluationProtocol(levels=(0.0, 1.0), metric="reconfig_success", records=(
                                  levels_record("vee_rotation_ppo_setpoints_levels.json", (1.0,), "vee_rotation", 0),
                                  levels_record("vee_rotation_ppo_setpoints_levels.json", (0.0,), "vee_rotation", 1))),
                              learning="all", baselines=("pid", "station_keeper"),
                              description="vee of 5 rotating the lead (leader to a trailing slot, the others up)",
                              test_randomisation={"initial_offset_m": 0.3}))
