"""The parts of the held-out evaluation (``formation-env evaluate``, :mod:`train.evaluation.evaluate`):
:mod:`train.evaluation.policy_loader` (``load_policy``: ``pid``, ``pid_formation``, an SB3 zip or an
RLlib checkpoint as an :class:`~train.evaluation.policy.EvalPolicy`), :mod:`train.evaluation.summary`
(per-policy summaries and the model-selection score), :mod:`train.evaluation.comparisons` (paired
comparisons against the baselines, seed groups), :mod:`train.evaluation.stats` (intervals and paired
tests, numpy only) and :mod:`train.evaluation.report` (tables and plots)."""
