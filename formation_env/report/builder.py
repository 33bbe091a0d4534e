"""The validation report: the project's numbers beside the thesis's, one markdown file with PNG
figures (``report.md``, ``report.json``, ``figures/``, ``replay/``).

Sections (each a function ``(ctx) -> Section``; :data:`SECTIONS` in order):

* ``ell_tables``: Tables 5.2-5.4 (``formation-env verify`` sections);
* ``aircraft``: trim A.5, open-loop modes A.6/A.7, closed-loop modes A.11/A.12;
* ``wake_field``: Trefftz planes (Figs. 4.7/4.8) and the nseg study (Figs. 4.10, 4.11, 4.13) with
  the thesis's conclusion that nseg = 10 is as good as 20;
* ``chapter5_sweeps``: the chapter 5.4 delta-wing sweeps (Figs. 5.6-5.8) and their findings;
* ``aerosonde_tailplane``: Figs. 6.3-6.6 and the thesis's statements about the tailplane;
* ``scenarios``: the chapter 6 / A.5.3 scenarios flown by the PID FCS: metrics against the
  thesis's statements and time histories (Figs. 6.8-6.23 style), 3D trajectories;
* ``replay``: Tacview ACMI export and an animated GIF of the reconfiguration, round-trip checked.

``quick=True`` shortens the scenarios, coarsens the sweeps and the GIF (used by the tests);
checks whose event the shortened runs do not reach are marked n/a.
"""

from __future__ import annotations

import datetime as _dt
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..io import atomic_write_json, atomic_write_text, prepare_output_dir
from .checks import Row, count, markdown_table, rows_from_verify_section

__all__ = ["ReportContext", "Section", "SECTIONS", "build_report"]


@dataclass
class ReportContext:
    out: Path
    quick: bool = False
    overwrite: bool = False
    log: object = print

    @property
    def fig_dir(self) -> Path:
        return self.out / "figures"

    def save(self, fig, name: str) -> Path:
        from ..plotting import save_figure

        return save_figure(fig, self.fig_dir / name, overwrite=self.overwrite)


@dataclass
class Section:
    key: str
    title: str
    intro: str = ""
    tables: list = field(default_factory=list)  # [(subtitle, [Row])]
    figures: list = field(default_factory=list)  # [(Path, caption)]
    files: list = field(default_factory=list)  # [(Path, description)] non-figure outputs
    data: dict = field(default_factory=dict)

    @property
    def rows(self) -> list[Row]:
        return [r for _, rows in self.tables for r in rows]

    def markdown(self, root: Path) -> str:
        c = count(self.rows)
        parts = [f"## {self.title}", f"*{c['ok']} within tolerance, {c['out']} outside, {c['n/a']} n/a*"]
        if self.intro:
            parts.append(self.intro)
        for sub, rows in self.tables:
            if sub:
                parts.append(f"### {sub}")
            parts.append(markdown_table(rows))
        for p, caption in self.figures:
            parts.append(f"![{caption}]({Path(p).relative_to(root).as_posix()})\n\n*{caption}*")
        for p, desc in self.files:
            parts.append(f"- [{Path(p).relative_to(root).as_posix()}]({Path(p).relative_to(root).as_posix()}): {desc}")
        return "\n\n".join(parts)


# ---------------------------------------------------------------- verification tables

def _verify(keys_titles):
    from ..verification.sections import available_sections

    avail = available_sections()
    tables, data = [], {}
    for key, title in keys_titles:
        if key not in avail:
            continue
        d = avail[key]()
        data[key] = d
        tables.append((title, rows_from_verify_section(d)))
    return tables, data


def ell_tables(ctx: ReportContext) -> Section:
    tables, data = _verify([("table_5_2", "Table 5.2: one wing in five poses (circulation G)"),
                            ("table_5_3", "Table 5.3: two wings seen from two frames (Vi, NED)"),
                            ("table_5_4", "Table 5.4: two wings at growing separation (G and Vi)")])
    return Section("ell_tables", "ELL verification (Tables 5.2-5.4)",
                   "Test wing of Table 5.1, V 25 m/s, alpha 5 deg, control-point evaluation, Kurylowich core. "
                   "G is the thesis's sign convention (minus ours). Vectors are summarised by their size and largest entry.",
                   tables, data=data)


def aircraft(ctx: ReportContext) -> Section:
    tables, data = _verify([("trim_a5", "Table A.5: trim, 25 m/s, 1000 m, 2 kg fuel (rad, rad/s)"),
                            ("modes_open", "Tables A.6/A.7: open-loop modes (real, |imag|), 1/s"),
                            ("modes_closed", "Tables A.11/A.12: closed-loop modes with the Appendix A FCS (real, |imag|), 1/s")])
    return Section("aircraft", "Aerosonde and flight control (Tables A.5-A.7, A.11, A.12)",
                   "Linearisations about the Table A.5 trim with the alpha-dot terms omitted (as Simulink linmod).",
                   tables, data=data)


# ---------------------------------------------------------------- wake figures

def wake_field(ctx: ReportContext) -> Section:
    from ..plotting.sweep_figures import NSEG_FIGURES, nseg_sweep_figure
    from ..plotting.wake_figures import trefftz_planes_figure

    sec = Section("wake_field", "Wake field and number of horseshoes (Figs. 4.7/4.8, 4.10, 4.11, 4.13)",
                  "Trefftz planes behind the Fig. 4.7 wing; the section 4.2.4 study of the follower's effective "
                  "induced velocity against the number of horseshoes nseg. The thesis concludes that nseg = 10 gives "
                  "as good results as nseg = 20; the check is max |Vi(10) - Vi(20)| <= 10 % of max |Vi(20)| per case.")
    p = ctx.save(trefftz_planes_figure(n=21 if ctx.quick else 41), "fig_4_7_4_8_trefftz_planes.png")
    sec.figures.append((p, "Figs. 4.7/4.8: induced velocity in Trefftz planes behind the wing (x = -1, -3, -10, -30 b)"))
    nsegs = (1, 4, 10, 20) if ctx.quick else (1, 2, 4, 6, 8, 10, 20)
    rows = []
    for fig_no in NSEG_FIGURES:
        fig, data = nseg_sweep_figure(fig_no, nsegs=nsegs, n_points=41 if ctx.quick else 121)
        sec.data[f"fig_{fig_no}"] = data
        p = ctx.save(fig, f"fig_{fig_no.replace('.', '_')}_nseg.png")
        sec.figures.append((p, f"Fig. {fig_no}: effective induced velocity against {data['caption']}, nseg = {', '.join(map(str, nsegs))}"))
        for case, cd in data["cases"].items():
            w10, w20 = np.asarray(cd["wind_body_mps"]["10"]), np.asarray(cd["wind_body_mps"]["20"])
            rel = float(np.abs(w10 - w20).max() / np.abs(w20).max())
            rows.append(Row(f"Fig. {fig_no} case {case}: max|Vi(10)-Vi(20)| / max|Vi(20)|", rel, "nseg 10 as good as 20",
                            "<= 0.10", rel <= 0.10, None, f"max |Vi(20)| {np.abs(w20).max():.3f} m/s"))
    sec.tables.append(("nseg 10 against nseg 20", rows))
    return sec


def chapter5_sweeps(ctx: ReportContext) -> Section:
    from ..plotting.wake_figures import sweeps_figure
    from ..verification.sweeps import lateral_sweep, longitudinal_sweep, vertical_sweep

    q = ctx.quick
    lat = lateral_sweep(np.round(np.linspace(-2, 2, 41), 6) if q else None)
    lon = longitudinal_sweep(np.round(np.linspace(-5, 2, 36), 6) if q else None)
    v1 = vertical_sweep(y_b=1.0)
    v75 = vertical_sweep(y_b=0.75)
    y, dcl = lat.coordinate, lat.increments["dCL"]
    z = v75.coordinate
    ymax = abs(float(y[np.argmax(dcl)]))
    sym = max(float(np.abs(dcl - dcl[::-1]).max()), float(np.abs(lat.wind_body[:, 1] + lat.wind_body[::-1, 1]).max()))
    behind = lon.coordinate <= -1.0
    rows = [
        Row("lateral (x -2b, z 0): y of the largest lift loss, b", float(y[np.argmin(dcl)]), 0.0, "abs 0.05",
            abs(float(y[np.argmin(dcl)])) <= 0.05, abs(float(y[np.argmin(dcl)])), f"dCL min {dcl.min():.3f}"),
        Row("lateral: |y| of the largest lift gain, b", ymax, 0.8, "abs 0.10 (thesis ~0.8b)", abs(ymax - 0.8) <= 0.1 + 1e-9,
            abs(ymax - 0.8), f"dCL max {dcl.max():.3f}"),
        Row("lateral: symmetry in y (dCL, Vi_y antisymmetric), max deviation", sym, 0.0, "abs 1e-9", sym <= 1e-9, sym),
        Row("vertical (x -2b, y 0.75b): z of the largest lift increment, b", float(z[np.argmax(v75.increments["dCL"])]),
            0.1, "abs 0.05", abs(float(z[np.argmax(v75.increments["dCL"])]) - 0.1) <= 0.05 + 1e-9,
            abs(float(z[np.argmax(v75.increments["dCL"])]) - 0.1)),
        Row("longitudinal (y b, z b/2), x <= -b: sidewash to starboard (Vi_y > 0)", bool(np.all(lon.wind_body[behind, 1] > 0)),
            True, "sign", bool(np.all(lon.wind_body[behind, 1] > 0))),
        Row("longitudinal, x <= -b: upwash (Vi_z < 0, body)", bool(np.all(lon.wind_body[behind, 2] < 0)), True, "sign",
            bool(np.all(lon.wind_body[behind, 2] < 0))),
    ]
    sweeps = [lat, lon, v1, v75]
    sec = Section("chapter5_sweeps", "Chapter 5.4 validation sweeps (Figs. 5.6-5.9)",
                  "Delta wing of Table 5.5 leading an identical follower, V 19.8171 m/s, alpha = theta = 8 deg, "
                  "quarter-chord evaluation, Kurylowich core, viscous AIC. The thesis's findings as checks.",
                  [("findings", rows)], data={s.name: s.as_dict() for s in sweeps})
    sec.figures.append((ctx.save(sweeps_figure(sweeps), "fig_5_6_5_9_validation_sweeps.png"),
                        "Figs. 5.6-5.9: follower's effective induced wind, rotational wind and lift increment along the sweeps"))
    return sec


def aerosonde_tailplane(ctx: ReportContext) -> Section:
    from ..plotting.sweep_figures import AEROSONDE_FIGURES, aerosonde_tailplane_figure

    sec = Section("aerosonde_tailplane", "Should the tailplane be modelled? (Figs. 6.3-6.6)",
                  "Two Aerosondes (Table 6.1), V 25 m/s, alpha = theta = 3 deg, rotational wind by Eq. 6.1, wing only "
                  "against wing + tailplane (tail arm 0.85 m: not given in the thesis). Rows: the thesis's statements "
                  "about the tailplane's contribution (mean over the follower behind the leader, x <= -b, for 6.3/6.4).")
    d = {}
    for fig_no in AEROSONDE_FIGURES:
        fig, data = aerosonde_tailplane_figure(fig_no, n_points=57 if ctx.quick else 141)
        d[fig_no] = data
        sec.figures.append((ctx.save(fig, f"fig_{fig_no.replace('.', '_')}_aerosonde_tailplane.png"),
                            f"Fig. {fig_no}: Aerosonde follower, {data['caption']}"))
    sec.data = {f"fig_{k}": v for k, v in d.items()}

    def delta(fig_no):
        data = d[fig_no]
        c = np.asarray(data["coordinate_b"])
        a = np.asarray(data["configs"]["wing only"]["wind_body_mps"])
        b = np.asarray(data["configs"]["wing + tailplane"]["wind_body_mps"])
        return (b - a)[c <= -1.0].mean(axis=0), a, b

    d63, _, _ = delta("6.3")
    d64, _, _ = delta("6.4")
    _, a65, b65 = delta("6.5")
    c65 = np.asarray(d["6.5"]["coordinate_b"])
    inner = np.abs(c65) <= 1.0
    rows = []
    for name, val, want in (("6.3: tailplane adds Vi_x > 0", d63[0], 1), ("6.3: tailplane adds Vi_y > 0", d63[1], 1),
                            ("6.3: tailplane adds Vi_z < 0", d63[2], -1), ("6.4 (tail -5 deg): adds Vi_x < 0", d64[0], -1),
                            ("6.4: adds Vi_y > 0", d64[1], 1), ("6.4: adds Vi_z > 0", d64[2], 1)):
        rows.append(Row(name + " (m/s)", float(val), "> 0" if want > 0 else "< 0", "sign", bool(np.sign(val) == want)))
    rows.append(Row("6.5: wing only, Vi_x <= 0 for |y| <= b: max Vi_x (m/s)", float(a65[inner, 0].max()), "<= 0", "sign",
                    bool(a65[inner, 0].max() <= 0)))
    rows.append(Row("6.5: wing + tailplane, Vi_x >= 0 for |y| <= b: min Vi_x (m/s)", float(b65[inner, 0].min()), ">= 0", "sign",
                    bool(b65[inner, 0].min() >= 0)))
    sec.tables.append(("tailplane contribution (thesis section 6.3)", rows))
    return sec


# ---------------------------------------------------------------- scenarios

QUICK_DURATION_S = 6.0


def _get(d: dict, *keys):
    for k in keys:
        if d is None:
            return None
        d = d.get(k)
    return d


def _scenario_rows(name: str, m: dict, quick: bool) -> list[Row]:
    from ..verification.thesis_values import thesis_values

    dur = m.get("duration_s", 0.0) if "duration_s" in m else _get(m, "wake_on", "duration_s")
    rows: list[Row] = []

    def reached(t):  # the run lasted long enough for the event at t
        return dur is not None and dur >= t

    if name == "tracking":
        ok = m["final_error_m"] <= 1.0 if reached(60.0) else None
        rows.append(Row("A.5.3 tracking: final position error (m)", m["final_error_m"], "converges onto the reference",
                        "<= 1.0 m at 60 s", ok, note=f"within 1 m from {m['time_to_within_1m_s']} s"))
        rows.append(Row("tracking: max bank (rad)", m["max_bank_rad"], "-", "info", None))
    elif name == "gust":
        for key, t_end, stop in (("gust_40s", 50.0, 100.0), ("gust_20s", 120.0, 150.0)):
            g = _get(m, "gusts", key)
            if g is None:
                rows.append(Row(f"{key}: recovery", None, "-", "-", None, note="not reached"))
                continue
            done = reached(stop)
            rt = g["recovery_time_s"]
            lim = g["thesis_recovery_within_s"]
            rows.append(Row(f"6.4 {key}: recovery to 0.25 m after the gust (s)", rt, f"within {lim} s", f"<= {lim} s",
                            (rt is not None and rt <= lim) if done else None))
            loss = g["max_altitude_loss_m"]
            rows.append(Row(f"6.4 {key}: altitude lost (m)", loss, "about 1 m", "0.5 .. 1.5 m",
                            (0.5 <= loss <= 1.5) if reached(t_end) else None))
            rows.append(Row(f"6.4 {key}: overtakes the reference after the gust", g["overtakes_after_gust"], True, "equal",
                            (g["overtakes_after_gust"] is True) if done else None))
    elif name == "formation_keeping":
        iw = _get(m, "wake_on", "follower", "induced_wind_ned_mps", "mean")
        fk = thesis_values()["section_6_5_formation_keeping"]["follower_offset_in_spans"]
        done = reached(10.0 + 1e-9)
        for k, (lab, want) in enumerate((("forward-wash (Vi_N > 0)", 1), ("sidewash to starboard (Vi_E > 0)", 1),
                                         ("upwash (Vi_D < 0)", -1))):
            v = None if iw is None else iw[k]
            rows.append(Row(f"6.5 follower at ({fk['x']}, {fk['y']}, {fk['z']}) b: mean {lab}, m/s", v,
                            "> 0" if want > 0 else "< 0", "sign", (bool(np.sign(v) == want)) if (done and v is not None) else None,
                            note="after 10 s"))
        wv = m.get("wake_vs_no_wake", {})
        for k in ("along_track_error_m", "altitude_error_m"):
            if k in wv:
                rows.append(Row(f"formation keeping rms {k}: wake on (off {wv[k]['wake_off']:.2g})", wv[k]["wake_on"], "-",
                                "info", None))
    elif name == "reconfiguration":
        lvl = m["level_in_north_at_s"]
        rows.append(Row("6.6: level with the leader in x at (s)", lvl, 34.0, "abs 5 s",
                        (lvl is not None and abs(lvl - 34.0) <= 5.0) if reached(40.0) else None,
                        None if lvl is None else abs(lvl - 34.0)))
        rows.append(Row("6.6: minimum separation (spans)", m["min_separation_spans"], "no collision", "> 1 span",
                        (m["min_separation_spans"] > 1.0) if reached(60.0) else None))
        rows.append(Row("6.6: final slot error (m)", m["final_slot_error_m"], "in the final slot", "<= 1 m",
                        (m["final_slot_error_m"] <= 1.0) if reached(60.0) else None))
    if quick:
        for r in rows:
            if r.ok is None and r.tolerance != "info":
                r.computed, r.note = None, "not reached: run shortened by --quick"
    return rows


def scenarios(ctx: ReportContext) -> Section:
    from ..plotting.scenario_figures import scenario_figures
    from ..plotting.trajectory3d import trajectory_3d_figure
    from ..replay.log import EpisodeLog
    from ..scenarios import scenario_names
    from ..runs.runner import run_scenario, scenario_metrics

    sec = Section("scenarios", "Scenarios flown by the thesis FCS (A.5.3, 6.4-6.6; Figs. 6.8-6.23 style)",
                  "Each scenario flown by the PID agents on the formation simulator (ELL wake on unless noted). "
                  + (f"**Quick run: every scenario cut to {QUICK_DURATION_S:g} s; the thesis's events are not reached "
                     "(n/a).** " if ctx.quick else "") + "Time histories as in the thesis: position parameters, air data, "
                  "Euler angles, controls, induced wind, ground track; 3D trajectories for the formations.")
    dur = QUICK_DURATION_S if ctx.quick else None
    sc_dir = ctx.fig_dir / "scenarios"
    for name in scenario_names():
        t0 = time.perf_counter()
        if name == "formation_keeping":
            runs = {"wake_on": run_scenario(name, True, dur), "wake_off": run_scenario(name, False, dur)}
            m = {"wake_on": scenario_metrics(runs["wake_on"]), "wake_off": scenario_metrics(runs["wake_off"])}
            on, off = m["wake_on"]["follower"], m["wake_off"]["follower"]
            m["wake_vs_no_wake"] = {k: {"wake_on": on[k]["rms"], "wake_off": off[k]["rms"]}
                                    for k in ("along_track_error_m", "off_track_error_m", "altitude_error_m")}
        else:
            run = run_scenario(name, None, dur)
            runs = {"wake_on" if run.wake else "wake_off": run}
            m = scenario_metrics(run)
        sec.data[name] = m
        sec.tables.append((name, _scenario_rows(name, m, ctx.quick)))
        paths = scenario_figures(runs, sc_dir, overwrite=ctx.overwrite)
        for p in paths:
            sec.figures.append((p, f"{name}: {p.stem[len(name) + 1:].replace('_', ' ')}"))
        first = next(iter(runs.values()))
        if first.scenario.n_vehicles > 1:
            log = EpisodeLog.from_scenario_run(first)
            sec.figures.append((ctx.save(trajectory_3d_figure(log), f"{name}_trajectory_3d.png"),
                                f"{name}: formation trajectories in 3D"))
        ctx.log(f"  scenario {name}: {time.perf_counter() - t0:.1f} s")
    return sec


def replay(ctx: ReportContext) -> Section:
    from ..replay import EpisodeLog, parse_acmi, write_acmi, write_animation
    from ..replay.acmi import geodetic_to_ned, object_id
    from ..runs.runner import run_scenario

    name = "reconfiguration"
    dur = QUICK_DURATION_S if ctx.quick else None
    log = EpisodeLog.from_scenario_run(run_scenario(name, None, dur))
    rdir = ctx.out / "replay"
    acmi = write_acmi(log, rdir / f"{name}.txt.acmi", overwrite=ctx.overwrite, stride=1 if ctx.quick else 5)
    rec = parse_acmi(acmi.read_text())
    lat0, lon0 = float(rec.globals["ReferenceLatitude"]), float(rec.globals["ReferenceLongitude"])
    err = 0.0
    for i in range(log.n_vehicles):
        t, lla = rec.positions(object_id(i))
        k = np.searchsorted(log.time_s, t - 1e-9)
        n, e = geodetic_to_ned(lla[:, 1], lla[:, 0], lat0, lon0)
        err = max(err, float(np.abs(np.stack([n, e, -lla[:, 2]], -1) - log.position_ned[k, i]).max()))
    gif = write_animation(log, rdir / f"{name}.gif", overwrite=ctx.overwrite, max_frames=8 if ctx.quick else 150,
                          fps=10.0, speedup=4.0)
    log.save_npz(rdir / f"{name}_log.npz", overwrite=ctx.overwrite)
    rows = [Row("ACMI round trip: max position error against the episode log (m)", err, 0.0, "<= 0.01 m", err <= 0.01, err,
                f"{len(rec.frames)} frames, objects {sorted(rec.objects)}")]
    sec = Section("replay", "Episode replay (Tacview ACMI 2.1, animated GIF)",
                  f"The {name} episode ({log.time_s[-1] + log.meta.get('dt_s', 0):.0f} s) for Tacview (open the "
                  "`.txt.acmi` file: every UAV with its attitude, and the ELL induced wind as the custom properties "
                  "InducedWindN/E/D, InducedOmegaX/Y/Z) and as a GIF (3D view with the trailing wake legs). "
                  "`formation-env replay --scenario NAME --gif` writes the same for any scenario.",
                  [("self-check", rows)])
    sec.files += [(acmi, "Tacview ACMI 2.1 text"), (gif, "animated 3D replay"), (rdir / f"{name}_log.npz", "episode log (numpy)")]
    sec.figures.append((gif, f"{name}: replay"))
    return sec


SECTIONS = {"ell_tables": ell_tables, "aircraft": aircraft, "wake_field": wake_field, "chapter5_sweeps": chapter5_sweeps,
            "aerosonde_tailplane": aerosonde_tailplane, "scenarios": scenarios, "replay": replay}


def build_report(out_dir=None, *, quick: bool = False, overwrite: bool = False, sections=None, log=print) -> dict:
    """Build the report into ``out_dir`` (default ``results/report-<timestamp>``; an existing
    non-empty directory is an error unless ``overwrite``). Returns the summary (also in report.json)."""
    out_dir = out_dir or f"results/report-{_dt.datetime.now().strftime('%Y%m%d-%H%M%S')}"
    keys = list(SECTIONS) if sections is None else list(sections)
    unknown = [k for k in keys if k not in SECTIONS]
    if unknown:
        raise ValueError(f"unknown report section(s) {unknown}; available: {list(SECTIONS)}")
    out = prepare_output_dir(out_dir, overwrite=overwrite)
    ctx = ReportContext(out, quick, overwrite, log)
    done: list[Section] = []
    timings = {}
    for k in keys:
        t0 = time.perf_counter()
        log(f"report: {k} ...")
        done.append(SECTIONS[k](ctx))
        timings[k] = time.perf_counter() - t0
    rows = [r for s in done for r in s.rows]
    total = count(rows)
    head = [
        "# formation-env validation report",
        f"Generated {_dt.datetime.now().isoformat(timespec='seconds')} by `formation-env report{' --quick' if quick else ''}`. "
        "Every row puts the project's number beside the thesis's (Saban, Cranfield) with the tolerance used; "
        "'within' is ok, **OUT** (outside the tolerance) or n/a (not applicable / not reached). SI units, radians.",
        f"**{total['ok']} of {total['total']} rows within tolerance, {total['out']} outside, {total['n/a']} n/a.**",
        "| section | within | outside | n/a |\n|---|---|---|---|\n" + "\n".join(
            f"| [{s.title}](#{_anchor(s.title)}) | {count(s.rows)['ok']} | {count(s.rows)['out']} | {count(s.rows)['n/a']} |"
            for s in done),
    ]
    md = "\n\n".join(head + [s.markdown(out) for s in done]) + "\n"
    atomic_write_text(out / "report.md", md, overwrite=overwrite)
    figures = [str(Path(p).relative_to(out)) for s in done for p, _ in s.figures]
    summary = {"quick": quick, "counts": total, "timings_s": timings, "figures": figures,
               "sections": {s.key: {"title": s.title, "counts": count(s.rows), "rows": [r.as_dict() for r in s.rows],
                                    "figures": [str(Path(p).relative_to(out)) for p, _ in s.figures],
                                    "files": [str(Path(p).relative_to(out)) for p, _ in s.files]} for s in done}}
    atomic_write_json(out / "report.json", _jsonable(summary), overwrite=overwrite)
    data = {s.key: s.data for s in done if s.data}
    atomic_write_json(out / "report_data.json", _jsonable(data), overwrite=overwrite)
    summary["out"] = str(out)
    return summary


def _anchor(title: str) -> str:
    import re

    return re.sub(r"[^a-z0-9 -]", "", title.lower()).replace(" ", "-")


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    if isinstance(x, (np.floating, float)):
        return None if not math.isfinite(float(x)) else float(x)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x
