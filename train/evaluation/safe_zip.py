"""Loading an SB3 policy zip without unpickling anything.

An SB3 zip is a ``data`` member (JSON, some of whose entries are cloudpickle blobs: the policy class, its
keyword arguments, the spaces, the schedules) and ``*.pth`` members (torch tensors). Unpickling a blob runs
whatever code its author put there, so a policy file from elsewhere could run code on load. This loader never
does: it reads the JSON as JSON, rebuilds each pickled entry from the readable description SB3 stores beside it,
for the forms this project's trainings write (PPO with ``MlpPolicy`` or the MAPPO ``CentralCriticPolicy``,
sb3-contrib's recurrent PPO with ``MlpLstmPolicy``, SAC, TD3; Box spaces; the standard activations) and hands those
to SB3 as ``custom_objects``, so that SB3 unpickles none of them; the tensors SB3 loads with ``torch.load(weights_only=True)``, which builds tensors and plain
containers only. A file that is not such a zip (not a zip, truncated, corrupt, another library's, an entry this
project does not write) is a ``ValueError`` saying it is not a readable policy, and nothing in it ran.
"""

from __future__ import annotations

import ast
import json
import zipfile
from pathlib import Path

__all__ = ["read_policy_zip", "load_sb3_model", "NOT_READABLE"]

NOT_READABLE = "is not a readable policy"

#: the policy classes this project's zips name: (algo, module SB3 records) -> (module, class)
_POLICIES = {("ppo", "stable_baselines3.common.policies"): ("stable_baselines3.common.policies", "ActorCriticPolicy"),
             ("ppo", "train.sb3.central_critic"): ("train.sb3.central_critic", "CentralCriticPolicy"),
             ("recurrent_ppo", "sb3_contrib.common.recurrent.policies"): ("sb3_contrib.common.recurrent.policies",
                                                                          "RecurrentActorCriticPolicy"),
             ("sac", "stable_baselines3.sac.policies"): ("stable_baselines3.sac.policies", "SACPolicy"),
             ("td3", "stable_baselines3.td3.policies"): ("stable_baselines3.td3.policies", "TD3Policy")}
_ACTIVATIONS = ("Tanh", "ReLU", "ELU", "LeakyReLU")
#: pickled entries that play no part in acting: replaced by None (SB3 rebuilds what it needs)
_UNUSED = {"_last_obs", "_last_episode_starts", "_last_original_obs", "ep_info_buffer", "ep_success_buffer",
           "action_noise", "replay_buffer_kwargs", "rollout_buffer_kwargs", "lr_schedule"}


def _refuse(label: str, why: str) -> ValueError:
    return ValueError(f"policy {label} {NOT_READABLE}: {why} (this project reads SB3 .zip files of its own trainings, "
                      "and unpickles nothing from them)")


def read_policy_zip(path: str | Path, label: str | None = None) -> dict:
    """The ``data`` JSON of the SB3 zip ``path`` (members checked: ``data`` and ``policy.pth``), or the
    ``ValueError`` saying it is not a readable policy."""
    label = repr(str(path)) if label is None else label
    try:
        with zipfile.ZipFile(path) as z:
            names = set(z.namelist())
            missing = [m for m in ("data", "policy.pth") if m not in names]
            if missing:
                raise _refuse(label, f"a zip without {missing} (not an SB3 model)")
            bad = z.testzip()  # every member's CRC: a corrupt member is caught here, not half-way into torch
            if bad is not None:
                raise _refuse(label, f"member {bad!r} is corrupt")
            data = json.loads(z.read("data").decode("utf-8"))
    except ValueError as exc:
        if NOT_READABLE in str(exc):
            raise
        raise _refuse(label, f"its 'data' member is not JSON ({exc})") from None
    except (zipfile.BadZipFile, zipfile.LargeZipFile, EOFError, OSError, KeyError, NotImplementedError) as exc:
        raise _refuse(label, f"not an intact zip ({type(exc).__name__}: {exc})") from None
    if not isinstance(data, dict):
        raise _refuse(label, "its 'data' member is not a JSON object")
    return data


def _literal(label: str, key: str, text):
    try:
        return ast.literal_eval(text) if isinstance(text, str) else text
    except (ValueError, SyntaxError, MemoryError, RecursionError):
        raise _refuse(label, f"entry {key} {text!r:.80} is not a plain value") from None


def _box(label: str, key: str, item: dict):
    import numpy as np
    from gymnasium import spaces

    if item.get(":type:") != "<class 'gymnasium.spaces.box.Box'>":
        raise _refuse(label, f"its {key} is a {item.get(':type:')}, not a gymnasium Box")
    shape = tuple(_literal(label, f"{key}._shape", item.get("_shape")))
    low, high = _literal(label, f"{key}.low_repr", item.get("low_repr")), _literal(label, f"{key}.high_repr",
                                                                                    item.get("high_repr"))
    if not all(isinstance(n, int) and 0 < n < 1_000_000 for n in shape) or not all(
            isinstance(x, (int, float)) for x in (low, high)):
        raise _refuse(label, f"its {key} is not a Box of one bound this project writes")
    dtype = item.get("dtype", "float32")
    if dtype not in ("float32", "float64"):
        raise _refuse(label, f"its {key} has dtype {dtype!r}")
    return spaces.Box(float(low), float(high), shape, dtype=np.dtype(dtype))


def _policy_kwargs(label: str, item: dict) -> dict:
    import torch.nn as nn

    out = {}
    for k, v in item.items():
        if k.startswith(":"):
            continue
        if k == "activation_fn":
            names = [a for a in _ACTIVATIONS if v == f"<class 'torch.nn.modules.activation.{a}'>"]
            if not names:
                raise _refuse(label, f"its activation_fn {v!r:.80} is not one of {list(_ACTIVATIONS)}")
            out[k] = getattr(nn, names[0])
        else:
            out[k] = _literal(label, f"policy_kwargs.{k}", v)
    return out


def _schedule_value(label: str, key: str, item: dict) -> float:
    """A schedule's (initial) value, read off its description: SB3's FloatSchedule(ConstantSchedule(val=x)) or
    LinearSchedule(start=x, ...); acting never calls it."""
    if "start" in item:
        return float(_literal(label, key, item["start"]))
    text = str(item.get("value_schedule", ""))
    if "val=" in text:
        return float(_literal(label, key, text.split("val=", 1)[1].split(")", 1)[0].split(",", 1)[0]))
    if "start=" in text:
        return float(_literal(label, key, text.split("start=", 1)[1].split(",", 1)[0].split(")", 1)[0]))
    raise _refuse(label, f"its {key} is a schedule this project does not write")


def safe_custom_objects(data: dict, algo: str, label: str) -> dict:
    """Every pickled entry of ``data`` rebuilt from its readable description (``custom_objects`` for SB3's
    ``load``), or the ``ValueError`` saying the file is not a readable policy."""
    import importlib

    out = {}
    for key, item in data.items():
        if not (isinstance(item, dict) and ":serialized:" in item):
            continue
        if key == "policy_class":
            where = _POLICIES.get((algo, item.get("__module__")))
            if where is None:
                raise _refuse(label, f"its policy class (module {item.get('__module__')!r}) is not one of this "
                                     f"project's for {algo}")
            out[key] = getattr(importlib.import_module(where[0]), where[1])
        elif key == "policy_kwargs":
            out[key] = _policy_kwargs(label, item)
        elif key in ("observation_space", "action_space"):
            out[key] = _box(label, key, item)
        elif key in ("learning_rate", "clip_range", "clip_range_vf"):
            out[key] = _schedule_value(label, key, item)
        elif key in ("rollout_buffer_class", "replay_buffer_class"):
            out[key] = None  # SB3's default buffer of the algorithm
        elif key == "train_freq":
            from stable_baselines3.common.type_aliases import TrainFreq, TrainFrequencyUnit

            n = _literal(label, "train_freq.frequency", item.get("frequency", "1"))
            unit = str(item.get("unit", "TrainFrequencyUnit.STEP"))
            out[key] = TrainFreq(int(n), TrainFrequencyUnit.EPISODE if "EPISODE" in unit else TrainFrequencyUnit.STEP)
        elif key in _UNUSED or key.startswith("_"):
            out[key] = None
        else:
            raise _refuse(label, f"its entry {key!r} is pickled, and this project's zips have no such entry")
    return out


def load_sb3_model(path: str | Path, algo: str | None = None, *, device: str = "cpu", label: str | None = None):
    """The SB3 model in ``path`` (``algo``: "ppo", "recurrent_ppo", "sac" or "td3"; None: read off the zip), loaded
    without unpickling (module docstring); anything else is the ``ValueError`` saying it is not a readable policy."""
    from stable_baselines3 import PPO, SAC, TD3

    label = repr(str(path)) if label is None else label
    data = read_policy_zip(path, label)
    classes = {"ppo": PPO, "recurrent_ppo": None, "sac": SAC, "td3": TD3}
    if algo is None:
        module = str((data.get("policy_class") or {}).get("__module__", ""))
        algo = ("sac" if ".sac." in module else "td3" if ".td3." in module
                else "recurrent_ppo" if module.startswith("sb3_contrib.common.recurrent") else "ppo")
    if algo not in classes:
        raise ValueError(f"algo must be one of {sorted(classes)}, got {algo!r}")
    if algo == "recurrent_ppo":  # sb3-contrib only for the policies that need it
        from ..recurrent import recurrent_ppo_class

        classes[algo] = recurrent_ppo_class()
    custom = safe_custom_objects(data, algo, label)
    try:
        return classes[algo].load(str(path), device=device, custom_objects=custom)
    except Exception as exc:  # noqa: BLE001 - a zip that passed the checks yet does not build: one line
        raise _refuse(label, f"SB3 could not build a {algo.upper()} model from it ({type(exc).__name__}: "
                             f"{str(exc)[:200]})") from None
