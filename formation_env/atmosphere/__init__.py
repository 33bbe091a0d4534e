"""The air the aircraft flies through: standard atmosphere, gravity, wind, gusts, turbulence.

* :mod:`.standard`: 1976 standard atmosphere (AeroSim's 100 m table).
* :mod:`.gravity`: constant g or WGS-84 normal gravity.
* :mod:`.wind`: :class:`WindInput`, the per-aircraft wind held over one integration step.
* :mod:`.gust`: the thesis's transient gust (section 6.4, Fig. 6.7) and its presets.
* :mod:`.dryden`: seeded Dryden turbulence (MIL-F-8785C), realised RMS equal to sigma.
* :mod:`.spectral_field`: one frozen von Karman or Dryden field per formation (random Fourier modes,
  carried with the steady wind) with rotational gusts: the env's default turbulence
  (:mod:`.spectral_field_kernels` the compiled kernels, :mod:`.spectral_theory` its statistics).
* :mod:`.frozen_field`: the "lanes" approximation of a frozen Dryden field (one lane per aircraft,
  Cholesky-mixed, Taylor-delayed).
"""

from .dryden import DrydenConfig, DrydenTurbulence, aircraft_seeds
from .gravity import G_CONSTANT, gravity_wgs84
from .gust import TransientGust, thesis_gust_20s, thesis_gust_40s, thesis_gusts
from .standard import standard_atmosphere
from .wind import WindInput, steady_wind

__all__ = [
    "DrydenConfig",
    "DrydenTurbulence",
    "aircraft_seeds",
    "G_CONSTANT",
    "gravity_wgs84",
    "TransientGust",
    "thesis_gust_20s",
    "thesis_gust_40s",
    "thesis_gusts",
    "standard_atmosphere",
    "WindInput",
    "steady_wind",
]
