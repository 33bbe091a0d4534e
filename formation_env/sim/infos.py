"""The info quantities of a :class:`~formation_env.sim.Simulation`, read from its state in one place:
:class:`InfoArrays`, every quantity as an array with the batch axis (``Simulation.info``), or of one formation
(:meth:`InfoArrays.formation`), whose per-UAV dicts are ``Simulation.infos(i)`` (:meth:`InfoArrays.per_vehicle`);
the flat info keys of the reward's terms, and the numpy separation the infos report."""

from __future__ import annotations

import math

import numpy as np

from ..aircraft.state import POS
from .energy import ENERGY_COLUMNS, N_ENERGY
from .energy import energy_account as _energy_account
from .kernels import separations_if_finite
from .observe import REWARD_TERMS

__all__ = ["InfoArrays", "INFO_REWARD_KEYS", "reward_info_key", "separation_each", "finite_values"]

_REWARD_TERM_NAMES = (*REWARD_TERMS, "total")


def reward_info_key(term: str) -> str:
    """The flat info key of a reward term: ``"slot"`` -> ``"reward_slot"`` (``"total"``: the reward itself)."""
    if term not in _REWARD_TERM_NAMES:
        raise ValueError(f"unknown reward term {term!r}; terms: {list(_REWARD_TERM_NAMES)}")
    return f"reward_{term}"


#: the flat info keys of the reward's terms, in REWARD_TERMS order, then ``reward_total``
INFO_REWARD_KEYS = tuple(reward_info_key(t) for t in _REWARD_TERM_NAMES)


class InfoArrays:
    """The info quantities of all formations as arrays (B, V, ...), read from the simulation's state at
    access time (nothing is computed unless read); with ``index`` (an int, from :meth:`formation`), those of
    formation ``index`` alone, without the batch axis. Never NaN: a diverged UAV's values read as its last
    finite ones (the kernel's outputs) or 0. ``sim``: the :class:`~formation_env.sim.Simulation` read."""

    def __init__(self, sim, index: int | None = None) -> None:
        self._sim = sim
        self._i = index

    def _at(self, a: np.ndarray) -> np.ndarray:
        """``a`` (batch axis first), or its formation ``index``."""
        return a if self._i is None else a[self._i]

    def formation(self, i: int) -> "InfoArrays":
        """The info quantities of formation ``i`` ((V, ...) arrays; ``time_s`` and ``collision`` scalars)."""
        return InfoArrays(self._sim, int(i))

    @property
    def time_s(self) -> np.ndarray | float:
        """(B,) episode time, s (a formation's: a float)."""
        if self._i is None:
            return self._sim.state.step * self._sim.dt
        return float(int(self._sim.state.step[self._i]) * self._sim.dt)  # steps < 2**53 convert exactly

    @property
    def slot_error_m(self) -> np.ndarray:
        """(B, V) distance from the slot, m: slot-frame components weighted by the scenario's axes
        (along-track only with a safe box); the reward's definition, the same at reset and after a step."""
        return self._at(self._sim.output.slot_error_m)

    @property
    def slot_error_ned_m(self) -> np.ndarray:
        """(B, V, 3) position minus demanded position, m NED."""
        s = self._sim.state
        return self._at(s.aircraft)[..., POS] - self._at(s.position_demand)

    @property
    def slot_error_track_m(self) -> np.ndarray:
        """(B, V, 3) position minus demanded position in the slot frame, m: along the track (x forward), lateral
        (y starboard), vertical (z down), unweighted. The slot frame is the scenario's: vehicle 0's demanded
        track (``slot_frame="leader_demand"``) or its measured ground track (``"leader_track"``), as the step's
        slot error and safe box use it. Non-finite states read as 0."""
        from ..frames import ned_to_track_frame

        sim, s = self._sim, self._sim.state
        demand = self._at(s.velocity_demand)
        ref = demand[..., 0, :] if sim.scenario.slot_frame == "leader_demand" else self._at(sim.velocity_ned())[..., 0, :]
        with np.errstate(invalid="ignore"):
            chi = np.arctan2(ref[..., 1], ref[..., 0])
            err = ned_to_track_frame(self._at(s.aircraft)[..., POS] - self._at(s.position_demand),
                                     np.where(np.isfinite(chi), chi, 0.0)[..., None])
        return np.where(np.isfinite(err), err, 0.0)

    @property
    def min_separation_m(self) -> np.ndarray:
        """(B, V) distance to the nearest other UAV, m (inf alone)."""
        if self._i is not None:
            return self._separation(self._i)[0]
        return np.stack([self._separation(i)[0] for i in range(self._sim.state.aircraft.shape[0])])

    def _separation(self, i: int) -> tuple[np.ndarray, bool]:
        """(formation ``i``'s (V,) separations, whether its state is finite): a finite formation's from one compiled
        call (bit for bit :func:`separation_each`'s, tested), which also says it is finite (then so are its
        infos, which derive from it); else :func:`separation_each` with the step's separations to fall back on."""
        x = self._sim.state.aircraft[i]
        sep = np.empty(x.shape[0])
        if separations_if_finite(x, sep):
            return sep, True
        return separation_each(x, self._sim.output.separation_m[i]), False

    @property
    def induced_wind_ned_mps(self) -> np.ndarray:
        """(B, V, 3) ELL effective induced wind, m/s NED."""
        return self._at(self._sim.state.induced_wind_ned)

    @property
    def induced_omega_body_rad_s(self) -> np.ndarray:
        """(B, V, 3) ELL effective rotational wind, rad/s body."""
        return self._at(self._sim.state.induced_omega_body)

    @property
    def fuel_kg(self) -> np.ndarray:
        """(B, V) fuel on board, kg."""
        return self._at(self._sim.state.aircraft)[..., 13]

    @property
    def gust_ned_mps(self) -> np.ndarray:
        """(B, V, 3) turbulence at each UAV, m/s NED."""
        return self._at(self._sim.state.gust_ned)

    @property
    def gust_omega_body_rad_s(self) -> np.ndarray:
        """(B, V, 3) rotational gusts at each UAV, rad/s body, the 6-DOF's convention (p_g, -q_g, -r_g; zero for
        the lanes and independent streams, which have none)."""
        return self._at(self._sim.state.gust_omega_body)

    @property
    def steady_wind_ned_mps(self) -> np.ndarray:
        """(B, 3) the episode's steady wind, m/s NED."""
        return self._at(self._sim.state.steady_wind)

    @property
    def velocity_demand_ned_mps(self) -> np.ndarray:
        """(B, V, 3) demanded ground velocities, m/s NED (vehicle 0's: the leader's demanded track)."""
        return self._at(self._sim.state.velocity_demand)

    @property
    def status(self) -> np.ndarray:
        """(B, V) int64 envelope status bits of the last physics step (0: inside)."""
        return self._at(self._sim.state.status)

    @property
    def collision(self) -> np.ndarray:
        """(B,) bool: the last decision ended in a collision."""
        return self._at(self._sim.output.collided)

    @property
    def crashed(self) -> np.ndarray:
        """(B, V) bool: the UAV left the envelope (or diverged) during the last decision."""
        return self._at(self._sim.output.crashed)

    @property
    def command(self) -> np.ndarray:
        """(B, V, 4) controls of the last physics step: elevator, aileron, rudder rad, throttle 0..1."""
        return self._at(self._sim.state.command)

    @property
    def induced_drag_saving(self) -> np.ndarray:
        """(B, V) induced-drag saving against the same UAV alone (0 unless the benefit is on)."""
        return self._at(self._sim.output.saving)

    @property
    def energy_account(self) -> np.ndarray:
        """(B, V, N_ENERGY) the energy account at the current state (:mod:`formation_env.sim.energy`,
        columns :data:`~formation_env.sim.energy.ENERGY_COLUMNS`): the 6-DOF's drag along the flight path
        alone and in formation, the ELL's induced-drag saving and isolated induced drag (N), and the ELL's and
        the 6-DOF's drag saving in % of the drag alone. Computed when read (one ELL solve per formation, with
        its coupling, and each UAV's isolated solve); zeros without wake."""
        sim, s = self._sim, self._sim.state
        out = np.zeros(s.aircraft.shape[:2] + (N_ENERGY,))
        if sim.wake_model is not None:
            p = sim.params
            omega = getattr(s, "gust_omega_body", None)
            omega = np.zeros_like(s.gust_ned) if omega is None else omega
            _energy_account(p.wake, p.wake_alone, p.coupling, p.aircraft, s.aircraft, np.ascontiguousarray(s.command),
                            np.ascontiguousarray(sim.ambient_wind()), np.ascontiguousarray(omega), out)
        return self._at(out)

    @property
    def drag_saving_pct_ell(self) -> np.ndarray:
        """(B, V) the ELL's predicted reduction of each UAV's total drag at its current state, % of its
        total drag alone (:attr:`energy_account`)."""
        return self.energy_account[..., ENERGY_COLUMNS.index("drag_saving_pct_ell")]

    @property
    def drag_saving_pct_6dof(self) -> np.ndarray:
        """(B, V) the reduction of the drag along the flight path the 6-DOF applies, formation against the
        same state and controls without the wake, % (:attr:`energy_account`)."""
        return self.energy_account[..., ENERGY_COLUMNS.index("drag_saving_pct_6dof")]

    @property
    def box_depth_m(self) -> np.ndarray:
        """(B, V) distance outside the UAV's safe box, m (0 inside or without a box)."""
        return self._at(self._sim.output.box_depth_m)

    @property
    def reward_terms(self) -> np.ndarray:
        """(B, V, T) the last decision's reward terms in REWARD_TERMS order (0 after a reset)."""
        return self._at(self._sim.output.reward_terms)

    @property
    def reward(self) -> np.ndarray:
        """(B, V) the last decision's reward (0 after a reset)."""
        return self._at(self._sim.output.reward)

    def per_vehicle(self) -> list[dict]:
        """The per-UAV info dicts of this formation (a :meth:`formation` view): ``Simulation.infos(i)``.

        Flat: every value is a Python scalar or a numpy array, and the keys are the same at reset and after every
        step (TorchRL builds its info specs from the reset infos). The reward's terms are ``reward_<term>``
        (:data:`INFO_REWARD_KEYS`; 0.0 at reset). The arrays are copies: the infos never share memory with the
        state (one copy per quantity for the whole formation; each UAV's info holds a row of it)."""
        if self._i is None:
            raise ValueError("per_vehicle: a view of one formation (InfoArrays.formation(i)) has per-UAV infos")
        separation, clean = self._separation(self._i)
        t = self.time_s
        # scalars through tolist(): the same Python floats, ints and bools as float()/int()/bool() per element
        slot, sep, fuel = self.slot_error_m.tolist(), separation.tolist(), self.fuel_kg.tolist()
        status, crashed, box = self.status.tolist(), self.crashed.tolist(), self.box_depth_m.tolist()
        terms, reward, collided = self.reward_terms.tolist(), self.reward.tolist(), bool(self.collision)
        saving = self.induced_drag_saving.tolist() if self._sim.benefit_enabled else None
        err_vec = self.slot_error_ned_m
        wind, omega = self.induced_wind_ned_mps.copy(), self.induced_omega_body_rad_s.copy()
        gust, gust_omega, command = self.gust_ned_mps.copy(), self.gust_omega_body_rad_s.copy(), self.command.copy()
        term_keys = INFO_REWARD_KEYS[:-1]
        result = []
        for v in range(len(slot)):
            info = {
                "time_s": t,
                "slot_error_m": slot[v],
                "slot_error_ned_m": err_vec[v],
                "min_separation_m": sep[v],
                "induced_wind_ned_mps": wind[v],
                "induced_omega_body_rad_s": omega[v],
                "fuel_kg": fuel[v],
                "gust_ned_mps": gust[v],
                "gust_omega_body_rad_s": gust_omega[v],
                "status": status[v],  # int64 -> int
                "collision": collided,
                "crashed": crashed[v],  # bool
                "command": command[v],
            }
            if saving is not None:
                info["induced_drag_saving"] = saving[v]
            info["box_depth_m"] = box[v]
            info.update(zip(term_keys, terms[v]))
            info[INFO_REWARD_KEYS[-1]] = reward[v]
            if not clean:
                finite_values(info)
            result.append(info)
        return result


def separation_each(x: np.ndarray, fallback: np.ndarray | None = None) -> np.ndarray:
    """(V,) distance from each UAV of one formation (x: (V, 16) states) to its nearest neighbour, m (inf
    alone); never NaN.

    Pairs with a non-finite position (a UAV that diverged: its episode is ending) are left out;
    a UAV with no finite pair gets ``fallback`` (the decision step's separation at the last finite
    positions, ``StepOutput.separation_m``) where that is not NaN, else inf."""
    with np.errstate(invalid="ignore", over="ignore"):
        d = np.linalg.norm(x[:, None, POS] - x[None, :, POS], axis=-1)
    d[~np.isfinite(d)] = np.inf
    np.fill_diagonal(d, np.inf)
    sep = d.min(axis=1)
    if fallback is not None and x.shape[0] > 1:
        fb = np.asarray(fallback, dtype=float)
        sep = np.where(~np.isfinite(sep) & ~np.isnan(fb), fb, sep)
    return sep


def finite_values(info: dict) -> None:
    """Infos never carry NaN or inf from a diverged UAV (its state is non-finite on the step that ends
    its episode): non-finite numbers become 0.0 and non-finite array entries 0.0, except
    ``min_separation_m``, which stays inf for a lone UAV (no neighbour)."""
    for key, value in info.items():
        if isinstance(value, float):
            if not math.isfinite(value) and not (key == "min_separation_m" and value == math.inf):
                info[key] = 0.0
        elif isinstance(value, np.ndarray) and value.dtype.kind == "f" and not np.all(np.isfinite(value)):
            info[key] = np.where(np.isfinite(value), value, 0.0)
