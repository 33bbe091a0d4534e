"""The SB3 callbacks of a training run: the learning curve, checkpoints, validation (model selection on
held-out episodes) and a plain progress log."""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..config import MIN_VALIDATION_EPISODES, VALIDATION_SEED_BASE
from .config import TrainConfig, make_env_config
from .run_files import run_metadata, save_checkpoint, save_model_atomic, write_text_atomic

from formation_env.rollout import FunctionPolicy

__all__ = ["build_callbacks"]


def build_callbacks(cfg: TrainConfig, run_dir: Path, state: dict, log: Callable[[str], None], progress_bar: bool):
    """The callbacks of a run and its validation callback (None when ``eval_freq`` is 0)."""
    from stable_baselines3.common.callbacks import BaseCallback

    from ..evaluation.episodes import eval_env_config, run_episodes
    from ..evaluation.summary import selection_score, summarise

    class Curve(BaseCallback):
        """Records every finished training episode (from infos['episode']) for curve.csv."""

        def _on_step(self) -> bool:
            for info in self.locals.get("infos", ()):
                ep = info.get("episode")
                if ep is not None:
                    state["curve"].append((int(self.num_timesteps), round(float(ep["r"]), 6), int(ep["l"])))
            return True

    class Checkpoint(BaseCallback):
        def __init__(self):
            super().__init__()
            self.next = (state["start_steps"] // cfg.checkpoint_freq + 1) * cfg.checkpoint_freq if cfg.checkpoint_freq else None

        def _on_step(self) -> bool:
            if self.next is not None and self.num_timesteps >= self.next:
                self.next += cfg.checkpoint_freq * max(1, math.ceil((self.num_timesteps - self.next + 1) / cfg.checkpoint_freq))
                save_checkpoint(self.model, run_dir, state)
            return True

    class Evaluate(BaseCallback):
        """Validation (model selection) on held-out seeds; keeps the best model (lowest selection score).

        The validation episodes are drawn exactly like the test set of ``formation-env evaluate``: the
        same ``eval_env_config`` with its defaults (wake on, Dryden sigma 1 m/s, no other randomisation,
        the scenario's duration), whatever the training's ``env_kwargs`` (turbulence, wake, initial
        offsets, randomisation) say; only the seeds differ (``VALIDATION_SEED_BASE + i`` vs
        ``TEST_SEED_BASE + i``, both out of the training's range). ``eval_episodes`` of them (32 by
        default). One exception, logged: a run whose ``env_kwargs`` shortens the episodes
        (``duration_s``: quick development runs, the tests) validates on episodes of that length, with
        the same seeds and conditions (like ``formation-env evaluate --duration``)."""

        def __init__(self):
            super().__init__()
            from formation_env.scenarios import get_scenario
            from formation_env.sim.layout import ObservationLayout

            self.next = (state["start_steps"] // cfg.eval_freq + 1) * cfg.eval_freq if cfg.eval_freq else None
            env = make_env_config(cfg)
            full = get_scenario(cfg.scenario).duration_s
            short = env.duration_s if env.duration_s is not None and env.duration_s < full else None
            # validated with the leader the run trains with (EnvConfig.leader_reference; None: the scenario's)
            self.layout = ObservationLayout.for_config(env)  # the run's observations
            self.config = eval_env_config(cfg.scenario, cfg.action_mode, control_hz=env.control_hz, duration_s=short,
                                          leader_reference=env.leader_reference, observation=self.layout)
            self.seeds = [VALIDATION_SEED_BASE + i for i in range(cfg.eval_episodes)]
            if short is not None:
                log(f"note: validation episodes cut to {short:g} s like the training's (the test set flies {full:g} s)")
            if cfg.eval_episodes < MIN_VALIDATION_EPISODES:
                log(f"note: validation on {cfg.eval_episodes} episodes (< {MIN_VALIDATION_EPISODES}): the model "
                    "selection follows noise more than skill")

        def _on_step(self) -> bool:
            if self.next is not None and self.num_timesteps >= self.next:
                self.next += cfg.eval_freq * max(1, math.ceil((self.num_timesteps - self.next + 1) / cfg.eval_freq))
                self.evaluate()
            return True

        def evaluate(self) -> None:
            from ..recurrent import chain_resets, model_policy

            model = self.model
            act, reset = model_policy(model)  # a recurrent model's LSTM state carried across the decisions
            if cfg.residual_on is not None:
                from .residual import residual_policy

                act, agent_reset = residual_policy(act, cfg.residual_on, layout=self.layout)
                reset = chain_resets(reset, agent_reset)
            if cfg.action_guard:
                from .guard import guarded

                act = guarded(act, cfg.action_guard, layout=self.layout)
            summ = summarise(run_episodes(FunctionPolicy(act, reset), self.config, self.seeds))
            score = selection_score(summ, cfg.selection_collision_cost)
            entry = {"num_timesteps": int(self.num_timesteps), "score": score, **summ}
            state["evaluations"].append(entry)
            for k in ("rms_slot_error_m", "return", "collisions", "reconfig_success_rate", "min_separation_m",
                      "induced_drag_saving", "box_outside_over_1s"):
                if k in summ:
                    self.logger.record(f"eval/{k}", summ[k])
            best = state.get("best_score")
            if best is None or score < best:
                state["best_score"], state["best_steps"] = score, int(self.num_timesteps)
                save_model_atomic(model, run_dir / "best_model.zip")
                write_text_atomic(run_dir / "best_model.json",
                                   json.dumps(run_metadata(cfg, self.num_timesteps, {"validation": entry}), indent=2) + "\n")
            write_text_atomic(run_dir / "evaluations.json", json.dumps(state["evaluations"], indent=2) + "\n")
            log(f"[eval] steps {self.num_timesteps}: RMS slot error {summ['rms_slot_error_m']:.3f} m, "
                f"collisions {summ['collisions']}, crashes {summ['crashes']}"
                + (f", reconfig success {summ['reconfig_success_rate']:.2f}" if "reconfig_success_rate" in summ else "")
                + (f", saving {summ['induced_drag_saving']:.3f}, >1 s outside the box {summ['box_outside_over_1s']}"
                   if "box_outside_over_1s" in summ else "")
                + (f", harvest {summ['harvest_ratio']:.3f} (lateral / vertical RMS {summ['rms_lateral_m']:.2f} / "
                   f"{summ['rms_vertical_m']:.2f} m)" if "harvest_ratio" in summ else "")
                + f", score {score:.3f} (best {state['best_score']:.3f} at {state['best_steps']})")

    class Progress(BaseCallback):
        """A plain progress line (when tqdm/rich are missing or the bar is off)."""

        def __init__(self):
            super().__init__()
            self.every = max(1, (state["total"] - state["start_steps"]) // 20)
            self.next = state["start_steps"] + self.every
            self.t0 = time.perf_counter()

        def _on_step(self) -> bool:
            if self.num_timesteps >= self.next:
                self.next += self.every
                recent = [r for _, r, _ in state["curve"][-50:]]
                rate = (self.num_timesteps - state["start_steps"]) / max(time.perf_counter() - self.t0, 1e-9)
                log(f"steps {self.num_timesteps}/{state['total']} ({rate:.0f}/s)"
                    + (f", mean return (last {len(recent)} episodes) {np.mean(recent):.1f}" if recent else ""))
            return True

    cbs = [Curve(), Checkpoint()]
    ev = Evaluate() if cfg.eval_freq else None
    if ev is not None:
        cbs.append(ev)
    if not progress_bar:
        cbs.append(Progress())
    return cbs, ev
