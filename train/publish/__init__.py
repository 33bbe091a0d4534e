"""Publishing trained policies: :mod:`train.publish.publish` copies a run's best model into
``train/policies/`` with its metadata, learning curve and validation history
(``python -m train.publish RUN_DIR NAME``), and :mod:`train.publish.report_committed` re-evaluates the
committed policies beside the PID baselines on the held-out test episodes, attaches the results to
their metadata and draws the README figures (``python -m train.publish.report_committed``); :mod:`train.publish.records`
makes the records of a task with its own evaluation (``python -m train.publish.records wake_surfing ...``). The exact
commands behind the committed runs are ``train/committed_runs.sh``."""
