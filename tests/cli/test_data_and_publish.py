"""The subcommands that replaced the ``python -m`` scripts reach the code they name with the arguments given
(``formation-env data ...``, ``formation-env verify --converged-saving``, ``formation-env publish ceilings``; the
other publish actions are run in tests/train/test_publish.py and test_levels_record.py). The heavy builders are
replaced by stand-ins here; their bad input is in tests/cli/test_cli_errors.py."""

from __future__ import annotations

import importlib

import pytest

from formation_env.cli import main
from formation_env.cli.data import optimum_units


def test_residual_table_builds_with_the_given_processes(tmp_path, monkeypatch, capsys):
    import formation_env.verification.residual_table as rt

    seen = {}

    def build_table(processes, progress):
        progress(1, 1)
        seen["processes"] = processes
        return {"values": []}

    def save_table(d, out, overwrite, provenance):
        seen.update(out=out, overwrite=overwrite, provenance=provenance)
        return out

    monkeypatch.setattr(rt, "build_table", build_table)
    monkeypatch.setattr(rt, "save_table", save_table)
    table = tmp_path / "table.npz"
    assert main(["data", "residual-table", "--table", str(table), "--processes", "3"]) == 0
    assert seen["processes"] == 3 and seen["out"] == table and seen["overwrite"] is False
    assert seen["provenance"].startswith("formation-env data residual-table --processes 3;")
    assert "1/1 planes" in capsys.readouterr().out


def test_optimum_rewrites_the_named_units_cache(tmp_path, monkeypatch, capsys):
    assert {"close_formation", "wake_surfing"} <= set(optimum_units())
    module = importlib.import_module(optimum_units()["wake_surfing"])
    written = []
    monkeypatch.setattr(module, "write_cache", lambda path, **kw: written.append(path) or path)
    assert main(["data", "optimum", "wake_surfing", "--cache", str(tmp_path / "c.json")]) == 0
    assert written == [str(tmp_path / "c.json")] and "wrote" in capsys.readouterr().out


def test_task_versions_records_nothing_twice(monkeypatch, capsys):
    import formation_env.tasks.versions as v

    monkeypatch.setattr(v, "record_new_versions", lambda: [])
    assert main(["data", "task-versions"]) == 0
    assert "already recorded" in capsys.readouterr().out


def test_saving_map_draws_to_the_path(tmp_path, monkeypatch, capsys):
    import formation_env.plotting.saving_map as sm

    monkeypatch.setattr(sm, "plot_map", lambda path: path)
    assert main(["data", "saving-map", str(tmp_path / "map.png")]) == 0
    assert str(tmp_path / "map.png") in capsys.readouterr().out


def test_verify_converged_saving_prints_one_line_per_lattice(monkeypatch, capsys):
    import formation_env.verification.converged_saving as cs

    monkeypatch.setattr(cs, "follower_maps", lambda cfg: None)
    monkeypatch.setattr(cs, "map_errors", lambda a, b: dict(
        saving=0.01, saving_off_plane=0.02, peak=0.3, peak_y_b=0.9, peak_z_b=0.1, local_maxima=1, lateral_maxima=1,
        load_weighted_y=0.01, load_weighted_z=0.02, effective_wind_y=0.1, effective_wind_z=0.2))
    assert main(["verify", "--converged-saving"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[0].startswith("against nseg 80") and len(lines) == 8 and lines[-1].startswith("nseg 160")


def test_publish_ceilings_prints_the_table(monkeypatch, capsys):
    ceilings = pytest.importorskip("train.evaluation.ceilings")
    seen = {}

    def rows(seeds, sigma):
        seen.update(seeds=seeds, sigma=sigma)
        return [{"controller": "station keeper", "harvest": 0.7, "rms_lateral_m": 0.2, "rms_vertical_m": 0.2,
                 "rms_along_track_m": 0.4, "surges": 0, "collisions": 0, "note": ""}]

    monkeypatch.setattr(ceilings, "ceiling_rows", rows)
    assert main(["publish", "ceilings", "--episodes", "2", "--seed", "7", "--sigma", "0.5"]) == 0
    assert seen == {"seeds": [7, 8], "sigma": 0.5}
    out = capsys.readouterr().out
    assert "2 episodes from seed 7, sigma 0.5 m/s" in out and "| station keeper | 0.700 |" in out
