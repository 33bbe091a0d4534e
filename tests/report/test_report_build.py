"""The validation report on the short (--quick) configuration: every section runs, every figure
file is produced and non-empty, the markdown references them, nothing is overwritten silently."""

import json
import re
from pathlib import Path

import pytest

from formation_env.cli import main
from formation_env.report import SECTIONS


@pytest.fixture(scope="module")
def report_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("report") / "r"
    rc = main(["report", "--quick", "--out", str(out)])
    assert rc in (0, 1)  # 1 = some row outside its tolerance (reported, not a crash)
    return out


def test_every_section_and_file(report_dir):
    summary = json.loads((report_dir / "report.json").read_text())
    assert summary["quick"] is True
    assert list(summary["sections"]) == list(SECTIONS)
    figures = summary["figures"]
    expected = {"fig_4_7_4_8_trefftz_planes.png", "fig_4_10_nseg.png", "fig_4_11_nseg.png", "fig_4_13_nseg.png",
                "fig_5_6_5_9_validation_sweeps.png", "fig_6_3_aerosonde_tailplane.png", "fig_6_4_aerosonde_tailplane.png",
                "fig_6_5_aerosonde_tailplane.png", "fig_6_6_aerosonde_tailplane.png", "formation_keeping_trajectory_3d.png",
                "reconfiguration_trajectory_3d.png", "reconfiguration.gif"}
    assert expected <= {Path(f).name for f in figures}
    for name in ("tracking", "gust", "formation_keeping", "reconfiguration"):
        for kind in ("positions", "air_data", "euler", "controls", "induced_wind", "trajectory"):
            assert f"figures/scenarios/{name}_{kind}.png" in figures
    for f in figures:
        p = report_dir / f
        assert p.is_file() and p.stat().st_size > 1000, f
        head = p.read_bytes()[:8]
        assert head.startswith(b"\x89PNG") or head.startswith(b"GIF8"), f
    for sec in summary["sections"].values():
        for f in sec["files"]:
            assert (report_dir / f).stat().st_size > 0


def test_markdown_references_every_figure_and_marks_rows(report_dir):
    md = (report_dir / "report.md").read_text()
    linked = set(re.findall(r"!\[[^\]]*\]\(([^)]+)\)", md))
    summary = json.loads((report_dir / "report.json").read_text())
    assert set(summary["figures"]) <= linked
    for title in ("Table 5.2", "Table 5.3", "Table 5.4", "Table A.5", "Tables A.6/A.7", "Tables A.11/A.12",
                  "Figs. 5.6-5.9", "Figs. 6.3-6.6"):
        assert title in md
    c = summary["counts"]
    assert c["total"] == c["ok"] + c["out"] + c["n/a"] and c["ok"] > 50


def test_thesis_tables_are_within_tolerance(report_dir):
    s = json.loads((report_dir / "report.json").read_text())["sections"]
    for key in ("ell_tables", "aircraft", "chapter5_sweeps", "wake_field", "replay"):
        assert s[key]["counts"]["out"] == 0, [r for r in s[key]["rows"] if r["ok"] is False]
    names = [r["name"] for r in s["aircraft"]["rows"]]
    assert any(n.startswith("alpha_rad") for n in names) and any("dutch_roll" in n for n in names)
    assert any("longitudinal.short_period" in n for n in names)  # closed loop (A.11)


def test_quick_scenarios_are_not_judged(report_dir):
    rows = json.loads((report_dir / "report.json").read_text())["sections"]["scenarios"]["rows"]
    assert rows and all(r["ok"] is None for r in rows)


def test_never_overwrites(report_dir):
    with pytest.raises(FileExistsError):
        from formation_env.report import build_report

        build_report(report_dir, quick=True, sections=["ell_tables"])
    assert main(["report", "--out", str(report_dir), "--section", "ell_tables"]) == 2


def test_unknown_section(tmp_path):
    assert main(["report", "--out", str(tmp_path / "x"), "--section", "nope"]) == 2
