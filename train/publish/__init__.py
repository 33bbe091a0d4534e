"""Publishing trained policies: :mod:`train.publish.publish` copies a run's best model into
``train/policies/`` with its metadata, learning curve and validation history
(``formation-env publish run RUN_DIR NAME``), :mod:`train.publish.levels_record` writes the record of a
multi-level evaluation (``formation-env publish levels``), :mod:`train.publish.recompute` recomputes the committed
statistics (``formation-env publish recompute``), and :mod:`train.publish.report_committed` re-evaluates the
committed policies beside the PID baselines on the held-out test episodes, attaches the results to
their metadata and draws the README figures (``formation-env publish committed``); :mod:`train.publish.records`
makes the records of a task with its own evaluation (``formation-env publish records wake_surfing ...``). The exact
commands behind the committed runs are ``train/committed_runs.sh``."""
