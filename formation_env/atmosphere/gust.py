"""The thesis's transient wind gust (section 6.4, Fig. 6.7) and its two presets.

A gust is a change of the steady NED wind with a smooth onset, a hold and a smooth decay:

    w(t) = A * s(t),  s = 0 before t0, 0.5 (1 - cos(pi (t - t0) / T_rise)) during the onset,
                      1 during the hold, 0.5 (1 + cos(pi (t - t_decay0) / T_decay)) during the decay,
                      0 afterwards,

so the wind and its first derivative are continuous (a raised-cosine ramp, the usual "1 - cos"
discrete-gust shape). The timings of the presets come from the text of section 6.4: the 40 s gust
starts at t = 10 s, reaches its maximum at t = 20 s and fades between t = 40 s and t = 50 s; the
20 s gust spans t = 100 s to 120 s (the same shape, time-scaled by one half). The amplitudes are
read from nothing: Fig. 6.7 is not transcribed, and the text says only that there is a vertical
component (about 1 m of altitude lost under the FCS, with the throttle saturating) and a lateral
one. The preset amplitude (east 2.0 m/s, down 1.5 m/s) is this project's choice, consistent with
that description (a 1.5 m/s downdraft exceeds the ~1 m/s climb margin at full throttle); every
component and duration is a parameter.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["TransientGust", "thesis_gust_40s", "thesis_gust_20s", "thesis_gusts", "THESIS_GUST_AMPLITUDE_NED"]

THESIS_GUST_AMPLITUDE_NED = (0.0, 2.0, 1.5)


@dataclass(frozen=True)
class TransientGust:
    """Raised-cosine onset, hold and decay of an NED wind change ``amplitude_ned`` (m/s)."""

    amplitude_ned: tuple[float, float, float] = THESIS_GUST_AMPLITUDE_NED
    start_s: float = 10.0
    rise_s: float = 10.0
    hold_s: float = 20.0
    decay_s: float = 10.0

    def __post_init__(self) -> None:
        amp = tuple(float(a) for a in self.amplitude_ned)
        if len(amp) != 3 or not all(np.isfinite(amp)):
            raise ValueError(f"TransientGust.amplitude_ned must be 3 finite numbers, got {self.amplitude_ned!r}")
        object.__setattr__(self, "amplitude_ned", amp)
        if not np.isfinite(self.start_s):
            raise ValueError("TransientGust.start_s must be finite")
        for name in ("rise_s", "decay_s"):
            if not (np.isfinite(getattr(self, name)) and getattr(self, name) > 0.0):
                raise ValueError(f"TransientGust.{name} must be positive, got {getattr(self, name)!r}")
        if not (np.isfinite(self.hold_s) and self.hold_s >= 0.0):
            raise ValueError(f"TransientGust.hold_s must be >= 0, got {self.hold_s!r}")

    @property
    def end_s(self) -> float:
        return self.start_s + self.rise_s + self.hold_s + self.decay_s

    @property
    def duration_s(self) -> float:
        return self.end_s - self.start_s

    def shape(self, t_s) -> np.ndarray:
        """The profile s(t) in [0, 1] (any shape of t)."""
        t = np.asarray(t_s, dtype=float)
        tau_up = np.clip((t - self.start_s) / self.rise_s, 0.0, 1.0)
        t_down = self.start_s + self.rise_s + self.hold_s
        tau_dn = np.clip((t - t_down) / self.decay_s, 0.0, 1.0)
        return 0.5 * (1.0 - np.cos(np.pi * tau_up)) * 0.5 * (1.0 + np.cos(np.pi * tau_dn))

    def wind_ned(self, t_s) -> np.ndarray:
        """Gust wind (m/s, NED) at time(s) ``t_s``: shape ``t.shape + (3,)``."""
        return self.shape(t_s)[..., None] * np.asarray(self.amplitude_ned)


def thesis_gust_40s(amplitude_ned=THESIS_GUST_AMPLITUDE_NED) -> TransientGust:
    """Section 6.4's first gust: onset 10-20 s, hold to 40 s, decay 40-50 s."""
    return TransientGust(amplitude_ned, start_s=10.0, rise_s=10.0, hold_s=20.0, decay_s=10.0)


def thesis_gust_20s(amplitude_ned=THESIS_GUST_AMPLITUDE_NED) -> TransientGust:
    """Section 6.4's second gust: 100-120 s, the 40 s shape time-scaled by 1/2."""
    return TransientGust(amplitude_ned, start_s=100.0, rise_s=5.0, hold_s=10.0, decay_s=5.0)


def thesis_gusts(t_s, amplitude_ned=THESIS_GUST_AMPLITUDE_NED) -> np.ndarray:
    """Both section 6.4 gusts of one run, summed (they do not overlap)."""
    return thesis_gust_40s(amplitude_ned).wind_ned(t_s) + thesis_gust_20s(amplitude_ned).wind_ned(t_s)
