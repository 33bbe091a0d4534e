"""Policy files are pickles; this project's loader unpickles none of them (train/evaluation/safe_zip.py): a zip whose
pickled entries would run code loads without running it (or is refused), a corrupt or truncated zip is one line
saying it is not a readable policy, and the project's own zips (PPO, MAPPO, SAC, TD3) act exactly as SB3's own
loader makes them act."""

import base64
import json
import os
import pickle
import zipfile
from pathlib import Path

import numpy as np
import pytest

from formation_env.cli import main
from train.evaluation.policy_loader import load_policy
from train.evaluation.safe_zip import NOT_READABLE, load_sb3_model

REPO = Path(__file__).resolve().parents[2]
COMMITTED = REPO / "train" / "policies" / "formation_keeping_ppo_setpoints_seed0.zip"
pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")


class _Payload:
    """Unpickling this makes a directory: the stand-in for code a hostile policy file runs."""

    def __init__(self, marker: str) -> None:
        self.marker = marker

    def __reduce__(self):
        return (os.mkdir, (self.marker,))


def _rewrite(src: Path, dst: Path, edit) -> Path:
    """A copy of the zip ``src`` whose ``data`` JSON is ``edit(data)``; the sidecar JSON copied beside it."""
    with zipfile.ZipFile(src) as z:
        members = {n: z.read(n) for n in z.namelist()}
    data = json.loads(members["data"])
    edit(data)
    members["data"] = json.dumps(data).encode()
    with zipfile.ZipFile(dst, "w") as z:
        for n, b in members.items():
            z.writestr(n, b)
    dst.with_suffix(".json").write_text(src.with_suffix(".json").read_text())
    return dst


def _blob(marker: Path) -> str:
    return base64.b64encode(pickle.dumps(_Payload(str(marker)))).decode()


def test_a_hostile_pickle_in_a_policy_zip_never_runs(tmp_path):
    from stable_baselines3 import PPO

    marker = tmp_path / "payload_ran"

    def plant(data):  # the payload in an entry the project's zips have, behind a harmless description
        data["lr_schedule"][":serialized:"] = _blob(marker)

    hostile = _rewrite(COMMITTED, tmp_path / "hostile.zip", plant)
    pol = load_policy(str(hostile))  # the entry is rebuilt from its description: the payload is never unpickled
    assert not marker.exists()
    obs = np.zeros((2, 53), np.float32)
    assert pol.act(obs).shape == (2, 4)
    PPO.load(str(hostile), device="cpu")  # SB3's own loader does unpickle it: the payload is live
    assert marker.is_dir()


def test_an_entry_the_project_never_writes_is_refused_unread(tmp_path):
    marker = tmp_path / "payload_ran"

    def plant(data):
        data["surprise"] = {":type:": "<class 'object'>", ":serialized:": _blob(marker)}

    hostile = _rewrite(COMMITTED, tmp_path / "hostile.zip", plant)
    with pytest.raises(ValueError, match=f"{NOT_READABLE}.*'surprise' is pickled"):
        load_policy(str(hostile))
    def other_class(data):
        data["policy_class"]["__module__"] = "somewhere.else"

    with pytest.raises(ValueError, match=f"{NOT_READABLE}.*policy class"):
        load_policy(str(_rewrite(COMMITTED, tmp_path / "other.zip", other_class)))
    assert not marker.exists()


@pytest.mark.parametrize("damage", ["text", "truncated", "empty", "flipped", "no_data"])
def test_a_corrupt_or_truncated_zip_is_one_line_saying_so(tmp_path, capsys, damage):
    raw = COMMITTED.read_bytes()
    bad = tmp_path / "policy.zip"
    if damage == "text":
        bad.write_text("not a zip")
    elif damage == "truncated":
        bad.write_bytes(raw[: len(raw) // 2])
    elif damage == "empty":
        bad.write_bytes(b"")
    elif damage == "flipped":  # one byte inside policy.pth's compressed data: its CRC no longer matches
        with zipfile.ZipFile(COMMITTED) as z:
            info = z.getinfo("policy.pth")
        at = info.header_offset + 30 + len(info.filename) + 200
        bad.write_bytes(raw[:at] + bytes([raw[at] ^ 0xFF]) + raw[at + 1:])
    else:
        with zipfile.ZipFile(bad, "w") as z:
            z.writestr("policy.pth", b"x")
    with pytest.raises(ValueError, match=NOT_READABLE):
        load_policy(str(bad))
    with pytest.raises(ValueError, match=NOT_READABLE):
        load_policy(str(bad), action_mode="setpoints")
    code = main(["evaluate", "--policy", str(bad), "--scenario", "formation_keeping", "--episodes", "1",
                 "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and NOT_READABLE in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("algo", ["sac", "td3"])
def test_the_projects_off_policy_zips_load_safely_and_act_as_sb3s(tmp_path, algo):
    from stable_baselines3 import SAC, TD3

    from formation_env.envs import FormationVecEnv

    cls = {"sac": SAC, "td3": TD3}[algo]
    venv = FormationVecEnv(1, scenario="formation_keeping", learning="followers", seed=0)
    model = cls("MlpPolicy", venv, policy_kwargs={"net_arch": [8]}, buffer_size=100, seed=0, device="cpu")
    path = tmp_path / f"{algo}.zip"
    model.save(str(path))
    safe, ref = load_sb3_model(path, algo), cls.load(str(path), device="cpu")
    obs = np.random.default_rng(0).normal(size=(4, venv.observation_space.shape[0])).astype(np.float32)
    assert np.array_equal(safe.predict(obs, deterministic=True)[0], ref.predict(obs, deterministic=True)[0])


def test_the_committed_policies_act_as_sb3_loads_them():
    from sb3_contrib import RecurrentPPO
    from stable_baselines3 import PPO, SAC

    loaders = {"ppo": PPO, "mappo": PPO, "sac": SAC, "recurrent_ppo": RecurrentPPO}
    for path in sorted((REPO / "train" / "policies").glob("*_seed0.zip")):
        algo = json.loads(path.with_suffix(".json").read_text())["env"]["algo"]
        algo = "ppo" if algo == "mappo" else algo  # MAPPO's policies are SB3 PPO's
        safe, ref = load_sb3_model(path, algo), loaders[algo].load(str(path), device="cpu")
        obs = np.random.default_rng(1).normal(size=(3, safe.observation_space.shape[0])).astype(np.float32)
        assert np.array_equal(safe.predict(obs, deterministic=True)[0], ref.predict(obs, deterministic=True)[0]), path
