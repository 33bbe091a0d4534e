"""formation-env: close-formation UAV flight simulation for reinforcement learning.

Layers (imports point down only): ``geometry`` -> ``wake`` (ELL) -> ``aircraft`` (Aerosonde
6-DOF) -> ``sim`` -> ``envs``. See README.md.
"""

__version__ = "0.1.0"
