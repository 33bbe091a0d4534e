"""Seeded Dryden turbulence (MIL-F-8785C transfer functions) with realised RMS equal to sigma.

Transfer functions (T = L / V, white noise input):

    H_u(s) = sigma_u sqrt(2 L_u / (pi V)) / (1 + T_u s)
    H_v(s) = sigma_v sqrt(L_v / (pi V)) (1 + sqrt(3) T_v s) / (1 + T_v s)^2      (same for w)

Each filter is discretised *exactly* for the step dt (matrix exponential plus the Van Loan noise
covariance), i.e. the output is the continuous Dryden process sampled every dt, and the output
map is scaled so that its stationary standard deviation is exactly ``sigma``. The filter starts
in its stationary distribution, so the RMS is right from t = 0.

Difference from AeroSim: AeroSim drives its filters with a zero-order-held unit-*variance*
Gaussian, which is white noise of intensity ~dt rather than 1, so its realised RMS is about
sigma sqrt(1.03 dt) (14 % of sigma at dt = 0.02 s). That quirk is deliberately not copied.
The filter time constants use a nominal airspeed fixed per aircraft (frozen-turbulence
assumption); the velocities are along the body axes (add them as ``WindInput.turbulence_body``).

Reproducibility: each aircraft draws from its own numpy Generator seeded explicitly, so
aircraft i of a batch gets bit-for-bit the same turbulence as a single run with the same seed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy.linalg import expm, solve_discrete_lyapunov

__all__ = ["DrydenConfig", "DrydenTurbulence", "aircraft_seeds", "mil_f_8785c_low_altitude"]

_FT = 0.3048


def mil_f_8785c_low_altitude(altitude_agl_m: float, wind_speed_20ft_mps: float):
    """MIL-F-8785C low-altitude intensities and scales: ((su, sv, sw) m/s, (Lu, Lv, Lw) m).

    The altitude is clipped to [10, 1000] ft (AeroSim's choice: the low-altitude forms are used at
    every altitude, frozen at 1000 ft above it).
    """
    h = float(np.clip(altitude_agl_m / _FT, 10.0, 1000.0))
    sigma_w = 0.1 * float(wind_speed_20ft_mps)
    sigma_uv = sigma_w / (0.177 + 0.000823 * h) ** 0.4
    l_uv = h / (0.177 + 0.000823 * h) ** 1.2 * _FT
    l_w = h * _FT
    return (sigma_uv, sigma_uv, sigma_w), (l_uv, l_uv, l_w)


@dataclass(frozen=True)
class DrydenConfig:
    """Intensities (m/s), scale lengths (m) along body x, y, z, nominal airspeed (m/s), step (s)."""

    sigma_mps: tuple[float, float, float] = (1.0, 1.0, 1.0)
    length_scale_m: tuple[float, float, float] = (533.0, 533.0, 533.0)
    airspeed_mps: float = 25.0
    dt: float = 0.02

    def __post_init__(self) -> None:
        for name in ("sigma_mps", "length_scale_m"):
            vals = tuple(float(x) for x in getattr(self, name))
            if len(vals) != 3 or not all(np.isfinite(vals)):
                raise ValueError(f"DrydenConfig.{name} must be 3 finite numbers")
            object.__setattr__(self, name, vals)
        if any(s < 0.0 for s in self.sigma_mps):
            raise ValueError("DrydenConfig.sigma_mps must be >= 0")
        if any(length <= 0.0 for length in self.length_scale_m):
            raise ValueError("DrydenConfig.length_scale_m must be positive")
        if not (np.isfinite(self.airspeed_mps) and self.airspeed_mps > 0.0):
            raise ValueError("DrydenConfig.airspeed_mps must be positive")
        if not (np.isfinite(self.dt) and self.dt > 0.0):
            raise ValueError("DrydenConfig.dt must be positive")

    @classmethod
    def low_altitude(cls, altitude_agl_m: float, wind_speed_20ft_mps: float, airspeed_mps: float = 25.0,
                     dt: float = 0.02) -> "DrydenConfig":
        """MIL-F-8785C low-altitude model from the altitude and the wind speed at 20 ft."""
        sigma, length = mil_f_8785c_low_altitude(altitude_agl_m, wind_speed_20ft_mps)
        return cls(sigma, length, airspeed_mps, dt)


def aircraft_seeds(seed: int, batch_size: int) -> list[int]:
    """Independent per-aircraft seeds derived from one seed (SeedSequence spawning)."""
    children = np.random.SeedSequence(int(seed)).spawn(int(batch_size))
    return [int(c.generate_state(1, dtype=np.uint64)[0]) for c in children]


def _first_order(tc: float, dt: float):
    a = np.exp(-dt / tc)
    return a, np.sqrt(1.0 - a * a)  # stationary variance 1


def _second_order(tc: float, dt: float):
    """Exact discretisation of (1 + sqrt3 T s)/(1 + T s)^2 scaled to unit stationary variance.

    Returns (Ad (2,2), G (2,2) lower-triangular noise gain, c (2,) output row, P chol (2,2))."""
    A = np.array([[-2.0 / tc, -1.0 / tc**2], [1.0, 0.0]])
    Bn = np.array([[1.0], [0.0]])
    c = np.array([np.sqrt(3.0) / tc, 1.0 / tc**2])
    # Van Loan: expm([[-A, B B^T], [0, A^T]] dt) gives Ad and the discrete noise covariance
    M = np.zeros((4, 4))
    M[:2, :2] = -A
    M[:2, 2:] = Bn @ Bn.T
    M[2:, 2:] = A.T
    E = expm(M * dt)
    Ad = E[2:, 2:].T
    Qd = Ad @ E[:2, 2:]
    Qd = 0.5 * (Qd + Qd.T)
    P = solve_discrete_lyapunov(Ad, Qd)
    c = c / np.sqrt(c @ P @ c)
    return Ad, np.linalg.cholesky(Qd), c, np.linalg.cholesky(0.5 * (P + P.T))


class DrydenTurbulence:
    """Dryden turbulence for B aircraft, advanced one ``dt`` per :meth:`step`.

    ``configs``: one DrydenConfig for all or one per aircraft; ``seeds``: one int per aircraft
    (use :func:`aircraft_seeds` to derive them from one seed). All configs must share dt.
    """

    _CHUNK = 1024

    def __init__(self, configs: DrydenConfig | Sequence[DrydenConfig], seeds: int | Sequence[int]):
        seed_list = [int(seeds)] if np.isscalar(seeds) else [int(s) for s in seeds]
        if isinstance(configs, DrydenConfig):
            configs = [configs] * len(seed_list)
        configs = list(configs)
        if len(configs) != len(seed_list) or not configs:
            raise ValueError(f"DrydenTurbulence: {len(configs)} configs for {len(seed_list)} seeds")
        dts = {c.dt for c in configs}
        if len(dts) != 1:
            raise ValueError("DrydenTurbulence: all configs must share one dt")
        self.dt = dts.pop()
        self.configs = tuple(configs)
        self.seeds = tuple(seed_list)
        n = len(configs)
        self._a_u = np.empty(n)
        self._g_u = np.empty(n)
        self._ad = np.empty((n, 2, 2, 2))  # [aircraft, axis v|w, 2, 2]
        self._gd = np.empty((n, 2, 2, 2))
        self._c = np.empty((n, 2, 2))
        self._p0 = np.empty((n, 2, 2, 2))
        self._sigma = np.array([c.sigma_mps for c in configs])
        cache: dict = {}
        for i, cfg in enumerate(configs):
            tcs = [length / cfg.airspeed_mps for length in cfg.length_scale_m]
            self._a_u[i], self._g_u[i] = _first_order(tcs[0], self.dt)
            for k, tc in enumerate(tcs[1:]):
                key = (tc, self.dt)
                if key not in cache:
                    cache[key] = _second_order(tc, self.dt)
                self._ad[i, k], self._gd[i, k], self._c[i, k], self._p0[i, k] = cache[key]
        self.reset()

    @property
    def batch_size(self) -> int:
        return len(self.seeds)

    def reset(self) -> None:
        """Restart every aircraft's stream from its seed, with the filters in their stationary state."""
        self._rngs = [np.random.default_rng(s) for s in self.seeds]
        self._buf = np.empty((self.batch_size, 0, 5))
        self._pos = 0
        n0 = self._draw()
        self._xu = n0[:, 0].copy()
        # stationary start: x = chol(P) n
        self._xvw = np.einsum("bkij,bkj->bki", self._p0, n0[:, 1:].reshape(-1, 2, 2))
        self._update_output()

    def _draw(self) -> np.ndarray:
        if self._pos >= self._buf.shape[1]:
            # each aircraft fills its own chunk from its own generator: batch == single runs
            self._buf = np.stack([g.standard_normal((self._CHUNK, 5)) for g in self._rngs])
            self._pos = 0
        out = self._buf[:, self._pos, :]
        self._pos += 1
        return out

    def _update_output(self) -> None:
        x = self._xvw
        vw = self._c[:, :, 0] * x[:, :, 0] + self._c[:, :, 1] * x[:, :, 1]
        self._value = self._sigma * np.concatenate([self._xu[:, None], vw], axis=1)

    @property
    def velocity_body(self) -> np.ndarray:
        """Current turbulence velocities (B, 3), body axes, m/s."""
        return self._value.copy()

    def step(self) -> np.ndarray:
        """Advance one dt; return the new (B, 3) velocities."""
        n = self._draw()
        self._xu = self._a_u * self._xu + self._g_u * n[:, 0]
        x, ad, gd = self._xvw, self._ad, self._gd
        nv = n[:, 1:].reshape(-1, 2, 2)
        x0 = ad[:, :, 0, 0] * x[:, :, 0] + ad[:, :, 0, 1] * x[:, :, 1] + gd[:, :, 0, 0] * nv[:, :, 0]
        x1 = (ad[:, :, 1, 0] * x[:, :, 0] + ad[:, :, 1, 1] * x[:, :, 1]
              + gd[:, :, 1, 0] * nv[:, :, 0] + gd[:, :, 1, 1] * nv[:, :, 1])
        self._xvw = np.stack([x0, x1], axis=-1)
        self._update_output()
        return self.velocity_body
