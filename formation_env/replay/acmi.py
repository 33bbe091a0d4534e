"""Tacview ACMI 2.1 text export of an episode, and a small parser (for tests and round trips).

File layout written::

    FileType=text/acmi/tacview
    FileVersion=2.1
    0,ReferenceTime=2024-01-01T00:00:00Z
    0,ReferenceLongitude=<lon0>
    0,ReferenceLatitude=<lat0>
    0,Title=...,DataSource=formation-env,Comments=...
    #0.00
    101,T=dlon|dlat|alt|roll|pitch|yaw,Name=Aerosonde,Type=Air+FixedWing,CallSign=uav_0,Color=...,<custom>
    ...

Positions: the flat-earth NED metres of the simulator are placed on the WGS-84 ellipsoid around
(lat0, lon0) with the local meridian and prime-vertical radii (:func:`ned_to_geodetic`); ACMI
longitudes and latitudes are written relative to the reference point (degrees), altitude in
metres (= -down). Attitude: roll, pitch, yaw = phi, theta, psi in degrees (Tacview: roll positive
right wing down, pitch positive nose up, yaw clockwise from true north, as 3-2-1 Euler angles).

Custom properties per object and frame (Tacview keeps unknown properties): the ELL effective
induced wind ``InducedWindN/E/D`` (NED, m/s), the rotational wind ``InducedOmegaX/Y/Z`` (body,
rad/s), and the ground speed ``GroundSpeed`` (m/s).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..io import atomic_write_text
from .log import EpisodeLog

__all__ = ["ned_to_geodetic", "geodetic_to_ned", "acmi_text", "write_acmi", "parse_acmi", "AcmiRecording",
           "object_id", "DEFAULT_REFERENCE"]

_WGS84_A = 6378137.0
_WGS84_E2 = 6.69437999014e-3
# Cranfield airfield (the thesis's home), a harmless default reference point.
DEFAULT_REFERENCE = {"latitude_deg": 52.0722, "longitude_deg": -0.6164, "time": "2024-01-01T00:00:00Z"}
# the colours ACMI 2.1 names, in the order of the figures' vehicle colours (matplotlib C0..C4)
_COLOURS = ("Blue", "Orange", "Green", "Red", "Violet")
_CUSTOM = ("InducedWindN", "InducedWindE", "InducedWindD", "InducedOmegaX", "InducedOmegaY", "InducedOmegaZ")


def _radii(lat0_rad: float) -> tuple[float, float]:
    s2 = math.sin(lat0_rad) ** 2
    rn = _WGS84_A / math.sqrt(1 - _WGS84_E2 * s2)  # prime vertical
    rm = _WGS84_A * (1 - _WGS84_E2) / (1 - _WGS84_E2 * s2) ** 1.5  # meridian
    return rm, rn


def ned_to_geodetic(north_m, east_m, lat0_deg: float, lon0_deg: float):
    """Flat-earth (north, east) metres about (lat0, lon0) -> (lat, lon) degrees (local radii)."""
    lat0 = math.radians(lat0_deg)
    rm, rn = _radii(lat0)
    lat = lat0_deg + np.degrees(np.asarray(north_m, dtype=float) / rm)
    lon = lon0_deg + np.degrees(np.asarray(east_m, dtype=float) / (rn * math.cos(lat0)))
    return lat, lon


def geodetic_to_ned(lat_deg, lon_deg, lat0_deg: float, lon0_deg: float):
    """Inverse of :func:`ned_to_geodetic`: (north, east) metres."""
    lat0 = math.radians(lat0_deg)
    rm, rn = _radii(lat0)
    north = np.radians(np.asarray(lat_deg, dtype=float) - lat0_deg) * rm
    east = np.radians(np.asarray(lon_deg, dtype=float) - lon0_deg) * rn * math.cos(lat0)
    return north, east


def object_id(vehicle_index: int) -> str:
    """ACMI object id (hexadecimal) of UAV ``vehicle_index``: 101, 102, ..."""
    return format(0x101 + int(vehicle_index), "x")


def _esc(text: str) -> str:
    return str(text).replace("\\", "\\\\").replace(",", "\\,").replace("\n", "\\\n")


def acmi_text(log: EpisodeLog, *, reference: dict | None = None, title: str | None = None, stride: int = 1,
              precision: int = 8) -> str:
    """The ACMI 2.1 text of ``log`` (every ``stride``-th sample, the last one always included)."""
    ref = {**DEFAULT_REFERENCE, **(reference or {})}
    lat0, lon0 = float(ref["latitude_deg"]), float(ref["longitude_deg"])
    if not (-89.0 < lat0 < 89.0 and -180.0 <= lon0 <= 180.0):
        raise ValueError(f"reference point out of range: lat {lat0}, lon {lon0}")
    stride = int(stride)
    if stride < 1:
        raise ValueError(f"stride must be >= 1, got {stride}")
    idx = list(range(0, log.n_samples, stride))
    if idx[-1] != log.n_samples - 1:
        idx.append(log.n_samples - 1)
    title = title or f"formation-env: {log.scenario or 'episode'}"
    lines = ["FileType=text/acmi/tacview", "FileVersion=2.1",
             f"0,ReferenceTime={ref['time']}", f"0,ReferenceLongitude={lon0:.7f}", f"0,ReferenceLatitude={lat0:.7f}",
             f"0,Title={_esc(title)}", "0,DataSource=formation-env", "0,Author=formation-env replay",
             "0,Comments=" + _esc("flat-earth NED about the reference point; custom properties InducedWindN/E/D "
                                  "(ELL effective induced wind, NED, m/s) and InducedOmegaX/Y/Z (body, rad/s)")]
    lat, lon = ned_to_geodetic(log.position_ned[..., 0], log.position_ned[..., 1], lat0, lon0)
    dlat, dlon = lat - lat0, lon - lon0
    alt = -log.position_ned[..., 2]
    att = np.degrees(log.euler_rad)
    gs = np.linalg.norm(log.velocity_ned, axis=-1)
    p = precision
    for n, k in enumerate(idx):
        lines.append(f"#{log.time_s[k]:.3f}")
        for i in range(log.n_vehicles):
            if not np.all(np.isfinite(log.position_ned[k, i])):
                continue
            t = f"{dlon[k, i]:.{p}f}|{dlat[k, i]:.{p}f}|{alt[k, i]:.3f}|{att[k, i, 0]:.3f}|{att[k, i, 1]:.3f}|{att[k, i, 2]:.3f}"
            wi, om = log.induced_wind_ned[k, i], log.induced_omega_body[k, i]
            custom = ",".join(f"{name}={val:.6g}" for name, val in zip(_CUSTOM, (*wi, *om)))
            head = (f",Name=Aerosonde,Type=Air+FixedWing,CallSign=uav_{i},Pilot=uav_{i},"
                    f"Color={_COLOURS[i % len(_COLOURS)]},Group=formation" if n == 0 else "")
            lines.append(f"{object_id(i)},T={t}{head},GroundSpeed={gs[k, i]:.3f},{custom}")
    return "\n".join(lines) + "\n"


def write_acmi(log: EpisodeLog, path, *, overwrite: bool = False, **kw):
    """Write :func:`acmi_text` to ``path`` (conventionally ``*.txt.acmi``), atomically."""
    return atomic_write_text(path, acmi_text(log, **kw), overwrite=overwrite)


@dataclass
class AcmiRecording:
    """A parsed ACMI text file: ``header`` (FileType, FileVersion), ``globals`` (object 0's
    properties), ``objects`` {id: latest non-T properties}, ``frames`` [(time, {id: props})],
    where ``props['T']`` is a list of floats (None for an empty field)."""

    header: dict = field(default_factory=dict)
    globals: dict = field(default_factory=dict)
    objects: dict = field(default_factory=dict)
    frames: list = field(default_factory=list)
    removed: list = field(default_factory=list)

    @property
    def times(self) -> np.ndarray:
        return np.array([t for t, _ in self.frames])

    def positions(self, obj: str) -> tuple[np.ndarray, np.ndarray]:
        """Times (K,) and absolute (lon, lat, alt) (K, 3) where ``obj`` has a T entry (relative
        coordinates resolved with the reference point; empty fields carried forward)."""
        lon0 = float(self.globals.get("ReferenceLongitude", 0.0))
        lat0 = float(self.globals.get("ReferenceLatitude", 0.0))
        ts, rows, last = [], [], [None] * 3
        for t, objs in self.frames:
            if obj in objs and "T" in objs[obj]:
                vals = objs[obj]["T"]
                last = [v if v is not None else last[j] for j, v in enumerate(vals[:3])]
                ts.append(t)
                rows.append([last[0] + lon0, last[1] + lat0, last[2]])
        return np.array(ts), np.array(rows, dtype=float)


def _split_unescaped(line: str, sep: str = ","):
    out, cur, i = [], [], 0
    while i < len(line):
        ch = line[i]
        if ch == "\\" and i + 1 < len(line):
            cur.append(line[i + 1])
            i += 2
            continue
        if ch == sep:
            out.append("".join(cur))
            cur = []
        else:
            cur.append(ch)
        i += 1
    out.append("".join(cur))
    return out


def parse_acmi(text: str) -> AcmiRecording:
    """Parse ACMI 2.x text (the subset this module writes plus comments, removals and line
    continuations). Raises ValueError on a malformed file."""
    if text.startswith("\ufeff"):
        text = text[1:]
    raw = text.splitlines()
    lines: list[str] = []
    for ln in raw:  # a trailing backslash continues the line
        if lines and lines[-1].endswith("\\") and not lines[-1].endswith("\\\\"):
            lines[-1] = lines[-1][:-1] + "\n" + ln
        else:
            lines.append(ln)
    rec = AcmiRecording()
    body = [ln for ln in lines if ln.strip() and not ln.startswith("//")]
    if len(body) < 2 or not body[0].startswith("FileType=") or not body[1].startswith("FileVersion="):
        raise ValueError("not an ACMI text file: the first lines must be FileType= and FileVersion=")
    rec.header["FileType"] = body[0].split("=", 1)[1].strip()
    rec.header["FileVersion"] = body[1].split("=", 1)[1].strip()
    if rec.header["FileType"] != "text/acmi/tacview" or not rec.header["FileVersion"].startswith("2."):
        raise ValueError(f"unsupported ACMI header {rec.header}")
    current = None
    for ln in body[2:]:
        if ln.startswith("#"):
            current = (float(ln[1:]), {})
            rec.frames.append(current)
            continue
        if ln.startswith("-"):
            rec.removed.append(ln[1:].strip())
            continue
        parts = _split_unescaped(ln)
        oid = parts[0].strip().lower()
        try:
            int(oid, 16)
        except ValueError:
            raise ValueError(f"bad object id in line {ln!r}") from None
        props = {}
        for part in parts[1:]:
            if "=" not in part:
                raise ValueError(f"bad property {part!r} in line {ln!r}")
            k, v = part.split("=", 1)
            props[k] = [float(x) if x != "" else None for x in v.split("|")] if k == "T" else v
        if oid == "0":
            rec.globals.update(props)
            continue
        if current is None:
            raise ValueError(f"object line before the first #time frame: {ln!r}")
        rec.objects.setdefault(oid, {}).update({k: v for k, v in props.items() if k != "T"})
        current[1].setdefault(oid, {}).update(props)
    return rec
