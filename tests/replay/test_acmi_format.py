"""The ACMI export against the Tacview ACMI 2.1 text format as documented
(https://www.tacview.net/documentation/acmi/), checked by a small independent reader written here
from the specification (not the project's own parser):

* the first two lines are exactly ``FileType=text/acmi/tacview`` and ``FileVersion=2.1``;
* every other line is a comment (``//``), a time frame ``#<seconds>`` (offset from ReferenceTime),
  an object removal ``-<id>`` or ``<id>,Property=Value,...``; object ids are hexadecimal (no
  ``0x`` prefix, no leading zeros), the global object being ``0``;
* global properties (ReferenceTime in ISO 8601 UTC, ReferenceLongitude/Latitude, Title, ...);
* ``T=Longitude|Latitude|Altitude|Roll|Pitch|Yaw``: longitude and latitude in degrees relative to
  the reference point, altitude in metres, roll (positive rolling right), pitch (positive nose up),
  yaw (clockwise from true north) in degrees;
* text values: a comma inside a value is escaped ``\\,``; a backslash at the very end of a line
  continues the value on the next line (a multi-line text).
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from formation_env.replay import EpisodeLog, acmi_text
from formation_env.runs.runner import run_scenario

GLOBAL_PROPERTIES = {"ReferenceTime", "RecordingTime", "Title", "Category", "Briefing", "Debriefing", "Comments",
                     "DataSource", "DataRecorder", "Author", "ReferenceLongitude", "ReferenceLatitude"}
# the object properties of the specification this export may use, and the custom ones it adds
OBJECT_TEXT_PROPERTIES = {"Name", "Type", "Parent", "Next", "CallSign", "Registration", "Squawk", "ICAO24", "Pilot",
                          "Group", "Country", "Coalition", "Color", "Shape", "Debug", "Label"}
CUSTOM = {"GroundSpeed", "InducedWindN", "InducedWindE", "InducedWindD", "InducedOmegaX", "InducedOmegaY", "InducedOmegaZ"}
COLORS = {"Red", "Orange", "Green", "Blue", "Violet"}  # the colours ACMI 2.1 names
TYPE_TAGS = {"Air", "Ground", "Sea", "Weapon", "Sensor", "Navaid", "Misc", "FixedWing", "Rotorcraft", "Heavy",
             "Medium", "Light", "Minor"}
HEX_ID = re.compile(r"^(0|[1-9a-fA-F][0-9a-fA-F]*)$")
ISO_UTC = re.compile(r"^\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}(\.\d+)?Z$")
PROP_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9]*$")
R_EARTH = 6_371_000.0  # a plain sphere: independent of the exporter's WGS-84 radii (differ by < 0.5 %)


# ------------------------------------------------------------------ independent reader
def logical_lines(text: str) -> list[str]:
    """Join physical lines: a line ending in a backslash continues on the next (the newline is
    kept in the value)."""
    out: list[str] = []
    pending = None
    for ln in text.split("\n"):
        if pending is not None:
            ln = pending + "\n" + ln
            pending = None
        if ln.endswith("\\"):
            pending = ln[:-1]
            continue
        out.append(ln)
    assert pending is None, "the file ends inside a continued line"
    return out


def split_fields(line: str) -> list[str]:
    """Split on commas not preceded by a backslash; ``\\,`` becomes a comma."""
    fields, cur, i = [], "", 0
    while i < len(line):
        if line[i] == "\\" and i + 1 < len(line) and line[i + 1] == ",":
            cur += ","
            i += 2
            continue
        if line[i] == ",":
            fields.append(cur)
            cur = ""
        else:
            cur += line[i]
        i += 1
    fields.append(cur)
    return fields


def read_acmi(text: str):
    """(globals, frames [(t, {id: {prop: value}})]) from ACMI 2.1 text, asserting the format."""
    assert not text.startswith("\ufeff") or text[1:].startswith("FileType=")
    lines = logical_lines(text.lstrip("\ufeff"))
    assert lines[0] == "FileType=text/acmi/tacview"
    assert lines[1] == "FileVersion=2.1"
    glob: dict[str, str] = {}
    frames: list = []
    for ln in lines[2:]:
        if ln == "" or ln.startswith("//"):
            continue
        if ln.startswith("#"):
            t = float(ln[1:])
            assert math.isfinite(t) and t >= 0.0, ln
            frames.append((t, {}))
            continue
        if ln.startswith("-"):
            assert HEX_ID.match(ln[1:]) and ln[1:] != "0", ln
            continue
        fields = split_fields(ln)
        oid = fields[0]
        assert HEX_ID.match(oid), f"object id {oid!r} is not hexadecimal without prefix or leading zeros"
        props = {}
        for f in fields[1:]:
            assert "=" in f, f"property without '=' in {ln!r}"
            name, value = f.split("=", 1)
            assert PROP_NAME.match(name), name
            props[name] = value
        if oid == "0":
            glob.update(props)
            continue
        assert frames, f"object line before the first time frame: {ln!r}"
        frames[-1][1].setdefault(oid, {}).update(props)
    return glob, frames


# ------------------------------------------------------------------ the export
@pytest.fixture(scope="module")
def log():
    return EpisodeLog.from_scenario_run(run_scenario("reconfiguration", None, 3.0))


@pytest.fixture(scope="module")
def parsed(log):
    return read_acmi(acmi_text(log))


def test_header_and_global_object(parsed):
    glob, _ = parsed
    assert set(glob) <= GLOBAL_PROPERTIES, set(glob) - GLOBAL_PROPERTIES
    assert ISO_UTC.match(glob["ReferenceTime"])
    lon0, lat0 = float(glob["ReferenceLongitude"]), float(glob["ReferenceLatitude"])
    assert -180.0 <= lon0 <= 180.0 and -90.0 <= lat0 <= 90.0


def test_time_frames_increase_and_object_ids_are_hex(log, parsed):
    _, frames = parsed
    times = np.array([t for t, _ in frames])
    assert times[0] == pytest.approx(0.0, abs=1e-9) and np.all(np.diff(times) > 0)
    np.testing.assert_allclose(times, log.time_s, atol=5e-4)  # seconds from ReferenceTime
    ids = sorted({oid for _, objs in frames for oid in objs})
    assert len(ids) == log.n_vehicles
    assert len({int(i, 16) for i in ids}) == len(ids)


def test_object_properties_are_the_documented_ones(parsed):
    _, frames = parsed
    first = frames[0][1]
    for oid, props in first.items():
        for name in ("Name", "Type", "Color"):
            assert name in props, (oid, name)
        assert set(props) - {"T"} <= OBJECT_TEXT_PROPERTIES | CUSTOM, set(props) - OBJECT_TEXT_PROPERTIES - CUSTOM
        assert set(props["Type"].split("+")) <= TYPE_TAGS and {"Air", "FixedWing"} <= set(props["Type"].split("+"))
        assert props["Color"] in COLORS, props["Color"]
    for _, objs in frames:
        for props in objs.values():
            for k in CUSTOM & set(props):
                assert math.isfinite(float(props[k]))


def test_transform_order_and_units(log, parsed):
    """T = lon|lat|alt|roll|pitch|yaw: degrees relative to the reference point, metres, degrees."""
    glob, frames = parsed
    lon0, lat0 = float(glob["ReferenceLongitude"]), float(glob["ReferenceLatitude"])
    for i, oid in enumerate(sorted({oid for _, objs in frames for oid in objs}, key=lambda s: int(s, 16))):
        rows = []
        for _, objs in frames:
            t = objs[oid]["T"].split("|")
            assert len(t) in (3, 5, 6, 9), t
            assert len(t) == 6, "this export writes the lon|lat|alt|roll|pitch|yaw form"
            rows.append([float(x) for x in t])
        rows = np.array(rows)
        lon, lat, alt = rows[:, 0] + lon0, rows[:, 1] + lat0, rows[:, 2]
        assert np.all(np.abs(lon) <= 180) and np.all(np.abs(lat) <= 90)
        # positions: a sphere's degrees back to metres match the log's NED within 0.5 % + 1 cm
        north = np.radians(lat - lat0) * R_EARTH
        east = np.radians(lon - lon0) * R_EARTH * math.cos(math.radians(lat0))
        p = log.position_ned[:, i]
        np.testing.assert_allclose(north, p[:, 0], rtol=5e-3, atol=1e-2)
        np.testing.assert_allclose(east, p[:, 1], rtol=5e-3, atol=1e-2)
        np.testing.assert_allclose(alt, -p[:, 2], atol=1e-3)  # metres, up positive
        assert 900.0 < alt.mean() < 1100.0  # metres, not feet or km (the scenarios fly at 1000 m)
        # attitude: degrees (not radians), roll = phi, pitch = theta, yaw = psi clockwise from north
        np.testing.assert_allclose(rows[:, 3:6], np.degrees(log.euler_rad[:, i]), atol=1e-3)
        v = log.velocity_ned[:, i]
        track = np.degrees(np.arctan2(v[:, 1], v[:, 0]))  # clockwise from north
        d = (rows[:, 5] - track + 180.0) % 360.0 - 180.0
        assert np.median(np.abs(d)) < 10.0
        # the flight direction: the latitude grows while flying north
        moving_north = v[:-1, 0] > 5.0
        assert np.all(np.diff(lat)[moving_north] > 0)


def test_text_values_escape_commas_and_continue_lines(log):
    title = "close formation, ELL wake\nsecond line, with a comma"
    text = acmi_text(log, title=title)
    glob, _ = read_acmi(text)
    assert glob["Title"] == title
    assert "close formation\\, ELL wake\\\nsecond line\\, with a comma" in text


def test_reader_rejects_what_the_spec_forbids():
    bad = ["FileType=text/acmi/tacview\nFileVersion=2.1\n#0\n0x101,T=0|0|0\n",
           "FileType=text/acmi/tacview\nFileVersion=2.1\n#0\n0101,T=0|0|0\n",
           "FileVersion=2.1\nFileType=text/acmi/tacview\n",
           "FileType=text/acmi/tacview\nFileVersion=2.1\n101,T=0|0|0\n"]
    for text in bad:
        with pytest.raises(AssertionError):
            read_acmi(text)
    glob, frames = read_acmi("FileType=text/acmi/tacview\nFileVersion=2.1\n0,Title=a\\,b\\\nc\n#0.5\n1a,T=1|2|3,Name=x\n")
    assert glob["Title"] == "a,b\nc" and frames == [(0.5, {"1a": {"T": "1|2|3", "Name": "x"}})]
