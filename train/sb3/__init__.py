"""Training with Stable-Baselines3 (PPO, SAC, TD3; sb3-contrib's recurrent PPO) on the native FormationVecEnv, the
default backend of ``formation-env train``: :mod:`train.sb3.config` (the run's configuration, :class:`TrainConfig`,
built from ``train/hyperparams/{ppo,recurrent_ppo,sac,td3}.yml``), :mod:`train.sb3.train` (the training loop, resume
and the run directory), :mod:`train.sb3.callbacks` (learning curve, checkpoints, validation, progress)
and :mod:`train.sb3.run_files` (the run directory's files, written atomically). What both backends
share (action modes, held-out seeds, YAML merging, the EnvConfig) is :mod:`train.config`."""
