"""Multi-agent PPO on Ray RLlib, locally or on a Ray cluster (``formation-env train --backend rllib``):
:mod:`train.rllib.backend` (the training loop and run directory; re-exports the other parts' names),
:mod:`train.rllib.config` (:class:`RLlibTrainConfig`, ``train/hyperparams/rllib_ppo.yml`` and the
PPOConfig), :mod:`train.rllib.cluster` (where Ray runs), :mod:`train.rllib.checkpoints`,
:mod:`train.rllib.policy` (inference as an :class:`~train.evaluation.policy.EvalPolicy`),
:mod:`train.rllib.bench` (sampling throughput) and :mod:`train.rllib.env` (the env as RLlib sees it).
Ray is optional: only :mod:`train.rllib.env` imports it at module level, and the other modules import
it (and that one) only inside functions, so importing this package costs nothing without Ray."""
