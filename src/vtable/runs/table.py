"""The run format's [table] table: which shaking table a run was made on.

A [table] names a preset (``preset = "eerc"``) and/or describes the table itself; keys
below a preset add to it or override it (docs/run-format.md). Every
physical key names its unit as a suffix, in SI or in the report's units
(``platen_mass_kg`` or ``platen_weight_kip``); weights are turned into masses by standard
gravity. Values are stored in SI in typed frozen dataclasses.

Errors (one line naming the file and the key): a value that is not a finite number, a
mass or an area that is not > 0, two spellings of one quantity, an unknown preset or
controller kind, a PID controller without gains, and an unknown key at any level: the
models read this table, so a key they would not use (a misspelt unit suffix, a gain
named without its unit) would change the physics without a word.

`vtable.runs.lab.lab_table` turns the description into the table the models read.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from vtable import units
from vtable.controllers import kinds
from vtable.errors import VtableError, did_you_mean
from vtable.params import presets
from vtable.params.base import check_number

#: degrees of freedom a platen may have (x along the shaking direction, z up)
DOFS = ("x", "y", "z", "roll", "pitch", "twist")
#: the catalog's controller kinds (`vtable.controllers.kinds`; a lab's own are registered
#: from its file)
CONTROLLER_KINDS = kinds.BUILT_IN
#: the keys of one [[table.controller.notch]] entry (a second-order notch)
NOTCH_KEYS = ("frequency_hz", "width_hz", "depth_db", "on")
NOTCH_PLACES = ("error", "drive")
#: the [table.controller] fields every kind reads: the shared loop of eqs 6.1-6.4
SHARED_CONTROL = ("kind", "displacement_gain", "p", "velocity_gain", "pressure_gain")
#: what the horizontal actuators' force channels measure: the net force the rod transmits
#: to the platen (a load cell) or the piston's pressure force A·ΔP (eq 6.3)
FORCE_MEASURED = ("load_cell", "delta_p")


@dataclass(frozen=True)
class _Key:
    """One quantity of the schema: its attribute, the TOML keys that may give it (each
    with its unit), and its bounds in SI."""

    attr: str
    keys: dict[str, str]
    minimum: float | None = 0.0     # SI; None: any sign
    inclusive: bool = False         # minimum allowed (>=) or not (>)
    integer: bool = False


def _level(d: Any, schema: tuple[_Key, ...], where: str, notes: list[str],
           subtables: tuple[str, ...] = (), plain: tuple[str, ...] = ()) -> dict[str, Any]:
    """Parse one level of [table]: attr -> SI value for the quantities it gives."""
    if not isinstance(d, dict):
        raise VtableError(f"{where}: expected a table, got {type(d).__name__}")
    by_key = {k: (q, u) for q in schema for k, u in q.keys.items()}
    out: dict[str, Any] = {}
    given: dict[str, str] = {}
    for k, v in d.items():
        if k in subtables or k in plain:
            continue
        if k not in by_key:
            known = sorted(by_key) + sorted(subtables) + sorted(plain)
            raise VtableError(f"{where}: unknown key {k!r}{did_you_mean(k, known)}; "
                              f"expected one of {', '.join(known)}")
        q, unit = by_key[k]
        if q.attr in given:
            raise VtableError(f"{where}: {given[q.attr]!r} and {k!r} give the same quantity; "
                              "give one")
        given[q.attr] = k
        if q.integer:
            if not isinstance(v, int) or isinstance(v, bool) or not 1 <= v <= 100:
                raise VtableError(f"{where}.{k}: expected a whole number from 1 to 100, "
                                  f"got {v!r}")
            out[q.attr] = v
            continue
        x = check_number(v, f"{where}.{k}", unit)
        if units.DIMENSIONS[unit] == "force" and q.attr in ("mass", "payload"):
            x = x / units.G  # a weight
        if q.minimum is not None:
            bad = x < q.minimum if q.inclusive else x <= q.minimum
            if bad:
                rel = ">=" if q.inclusive else ">"
                raise VtableError(f"{where}.{k}: must be {rel} "
                                  f"{units.from_si(q.minimum, unit):g}, got {v!r}")
        out[q.attr] = x
    return out


# ---- the schema -----------------------------------------------------------------------
_TOP = (
    _Key("mass", {"platen_mass_kg": "kg", "platen_weight_kip": "kip", "platen_weight_lb": "lb",
                  "platen_weight_n": "N", "platen_weight_kn": "kN"}),
    _Key("pitch_inertia", {"pitch_inertia_kg_m2": "kg-m2",
                           "pitch_inertia_kip_in_s2": "kip-in-s2",
                           "pitch_inertia_lb_in_s2": "lb-in-s2"}),
    _Key("com_height", {"com_height_m": "m", "com_height_in": "in", "com_height_mm": "mm"},
         minimum=None),
)
_HORIZONTAL = (
    _Key("count", {"count": "1"}, integer=True),
    _Key("piston_area", {"piston_area_m2": "m2", "piston_area_in2": "in2"}),
    _Key("oil_volume", {"oil_volume_m3": "m3", "oil_volume_in3": "in3"}),
    _Key("bulk_modulus", {"bulk_modulus_pa": "Pa", "bulk_modulus_psi": "psi",
                          "bulk_modulus_mpa": "MPa"}),
    _Key("leakage", {"leakage_m3_per_s_pa": "m3/s/Pa", "leakage_in3_per_s_psi": "in3/s/psi"},
         inclusive=True),
    _Key("valve_flow_gain", {"valve_flow_gain_m3_per_s_v": "m3/s/V",
                             "valve_flow_gain_in3_per_s_v": "in3/s/V"}),
    _Key("valve_time_constant", {"valve_time_constant_s": "s", "valve_time_constant_ms": "ms"},
         inclusive=True),
    _Key("damping", {"damping_n_s_per_m": "N-s/m", "damping_lb_s_per_in": "lb-s/in",
                     "damping_kip_s_per_in": "kip-s/in"}, inclusive=True),
)
_CONTROLLER = (
    # three_variable: knob positions of report Table 3.2 (dimensionless dial settings)
    _Key("gain", {"gain": "1"}, inclusive=True),
    _Key("delta_p", {"delta_p": "1"}, inclusive=True),
    _Key("rate", {"rate": "1"}, inclusive=True),
    # physical gains (either kind)
    _Key("displacement_gain", {"displacement_gain_v_per_m": "V/m",
                               "displacement_gain_v_per_in": "V/in"}, inclusive=True),
    _Key("velocity_gain", {"velocity_gain_v_s_per_m": "V-s/m",
                           "velocity_gain_v_s_per_in": "V-s/in"}, inclusive=True),
    _Key("acceleration_gain", {"acceleration_gain_v_s2_per_m": "V-s2/m",
                               "acceleration_gain_v_s2_per_in": "V-s2/in"}, inclusive=True),
    _Key("pressure_gain", {"pressure_gain_v_per_pa": "V/Pa", "pressure_gain_v_per_psi": "V/psi"},
         inclusive=True),
    # pid on the displacement error (in volts after displacement_gain)
    _Key("p", {"p": "1"}, inclusive=True),
    _Key("i", {"i_per_s": "1/s"}, inclusive=True),
    _Key("d", {"d_s": "s"}, inclusive=True),
    _Key("feedforward_velocity", {"feedforward_velocity_s": "s"}, inclusive=True),
    _Key("feedforward_acceleration", {"feedforward_acceleration_s2": "s2"}, inclusive=True),
    _Key("derivative_filter", {"derivative_filter_s": "s"}, inclusive=True),
    # tvc: the reference generator (second order)
    _Key("reference_frequency", {"reference_frequency_hz": "Hz"}),
    _Key("reference_damping", {"reference_damping": "1"}),
)
_LIMITS = (
    _Key("stroke", {"stroke_m": "m", "stroke_mm": "mm", "stroke_in": "in"}),
    _Key("velocity", {"velocity_m_per_s": "m/s", "velocity_in_per_s": "in/s"}),
    _Key("acceleration", {"acceleration_m_per_s2": "m/s2", "acceleration_g": "g"}),
    _Key("payload", {"payload_kg": "kg", "payload_kip": "kip", "payload_lb": "lb"}),
)


@dataclass(frozen=True)
class HorizontalActuators:
    """The actuators along x, per actuator (the models lump `count` of them), SI."""

    count: int | None = None
    piston_area: float | None = None          # m²
    oil_volume: float | None = None           # m³, both chambers
    bulk_modulus: float | None = None         # Pa
    leakage: float | None = None              # m³/s/Pa
    valve_flow_gain: float | None = None      # m³/s/V
    valve_time_constant: float | None = None  # s
    damping: float | None = None              # N s/m
    force_measured: str | None = None         # FORCE_MEASURED (None: "load_cell")


@dataclass(frozen=True)
class ControllerDescription:
    """The horizontal controller: ``three_variable`` (report Table 3.2 knob positions
    and/or physical gains) or ``pid`` (gains on the displacement error)."""

    kind: str
    gain: float | None = None
    delta_p: float | None = None
    rate: float | None = None
    displacement_gain: float | None = None    # V/m
    velocity_gain: float | None = None        # V s/m
    acceleration_gain: float | None = None    # V s²/m
    pressure_gain: float | None = None        # V/Pa
    p: float | None = None                    # 1
    i: float | None = None                    # 1/s
    d: float | None = None                    # s
    feedforward_velocity: float | None = None       # s
    feedforward_acceleration: float | None = None   # s²
    derivative_filter: float | None = None          # s: τ_f of D(s) = s/(τ_f s + 1)
    reference_frequency: float | None = None        # Hz: the reference generator's f_g
    reference_damping: float | None = None          # 1: its ζ_g
    notches: tuple[Notch, ...] | None = None
    #: a lab's own kind's keys (`ControllerKind.user_keys`), SI
    extra: dict[str, float] | None = None


@dataclass(frozen=True)
class Notch:
    """A notch filter of the controller: centre `frequency` (Hz), -3 dB `width` (Hz),
    `depth_db` at the centre, on the displacement "error" or on the "drive"."""

    frequency: float
    width: float
    depth_db: float = 40.0
    on: str = "error"


@dataclass(frozen=True)
class TableLimits:
    """Performance limits (stroke and velocity as ± amplitudes), SI."""

    stroke: float | None = None        # m
    velocity: float | None = None      # m/s
    acceleration: float | None = None  # m/s²
    payload: float | None = None       # kg
    band: tuple[float, float] | None = None  # Hz


@dataclass(frozen=True)
class TableDescription:
    """What a run's [table] says, in SI; None where it says nothing."""

    preset: str | None = None
    dofs: tuple[str, ...] | None = None
    mass: float | None = None            # kg, platen
    pitch_inertia: float | None = None   # kg m², about the horizontal actuator line
    com_height: float | None = None      # m above the horizontal actuator line
    horizontal: HorizontalActuators | None = None
    controller: ControllerDescription | None = None
    limits: TableLimits | None = None
    notes: tuple[str, ...] = dataclasses.field(default=(), compare=False)


# ---- presets: one registry ------------------------------------------------------------
def _eerc() -> dict[str, Any]:
    """The EERC 20 x 20 ft table (data/eerc.toml): §2.2, Tables 2.1, 2.2, 3.2, 8.1, B.5."""
    t = presets.eerc_table()
    g, s, sp, std = t.geometry, t.servo, t.specs, t.standard.horizontal
    return {
        "dofs": ["x", "z", "roll", "pitch", "twist"],  # the five controllers of Table 3.2
        "platen_mass_kg": g.mass,                       # §2.2: 100 kips
        "pitch_inertia_kg_m2": g.pitch_inertia,         # Table 8.1: 1251 kip-in-s²
        "horizontal": {"count": 3, "piston_area_m2": s.area,   # Tables 2.1, B.5 (each)
                       "oil_volume_m3": s.volume, "bulk_modulus_pa": s.beta,
                       "leakage_m3_per_s_pa": s.k_ct},       # B.5 flow-pressure coefficient
        "controller": {"kind": "three_variable", "gain": std.gain, "delta_p": std.delta_p,
                       "rate": std.rate},                    # Table 3.2 standard settings
        "limits": {"stroke_m": sp.stroke_h, "velocity_m_per_s": sp.velocity_h,
                   "acceleration_m_per_s2": sp.acceleration_h, "payload_kg": sp.weight_capacity
                   / units.G, "band_hz": [0.0, sp.bandwidth]},  # Table 2.2
    }


def _data(name: str) -> Callable[[], dict[str, Any]]:
    """A preset written as a [table] description in params/data/NAME.toml."""
    def load() -> dict[str, Any]:
        return {k: v for k, v in presets.data(name).items() if k != "source"}
    return load


#: table presets by name (a run's [table] preset)
TABLE_PRESETS: dict[str, Callable[[], dict[str, Any]]] = {"eerc": _eerc,
                                                          "lnec-st1d": _data("lnec_st1d")}


# ---- parsing --------------------------------------------------------------------------
def _sub(where: str, key: str) -> str:
    """'RUN.toml [table]' -> 'RUN.toml [table.horizontal]'."""
    return f"{where[:-1]}.{key}]" if where.endswith("]") else f"{where}.{key}"


def _dofs(v: Any, where: str) -> tuple[str, ...]:
    if not isinstance(v, list) or not v or not all(isinstance(x, str) for x in v):
        raise VtableError(f"{where}.dofs: expected a non-empty list of names from "
                          f"{', '.join(DOFS)}, got {v!r}")
    bad = [x for x in v if x not in DOFS]
    if bad:
        raise VtableError(f"{where}.dofs: {bad[0]!r} is not a platen motion; expected "
                          f"{', '.join(DOFS)}")
    if len(set(v)) != len(v):
        raise VtableError(f"{where}.dofs: a motion is listed twice")
    return tuple(v)


def _band(v: Any, where: str) -> tuple[float, float]:
    if not isinstance(v, list) or len(v) != 2:
        raise VtableError(f"{where}: expected [low, high] in Hz, got {v!r}")
    lo = check_number(v[0], where, "Hz")
    hi = check_number(v[1], where, "Hz")
    if not 0 <= lo < hi:
        raise VtableError(f"{where}: expected 0 <= low < high, got [{lo:g}, {hi:g}]")
    return lo, hi


def _parse(d: dict[str, Any], where: str, notes: list[str]) -> dict[str, Any]:
    """One [table] dict (a preset's or the user's) -> attr values, nested per sub-table."""
    subs = ("horizontal", "controller", "limits")
    out = _level(d, _TOP, where, notes, subtables=subs, plain=("preset", "dofs"))
    if "dofs" in d:
        out["dofs"] = _dofs(d["dofs"], where)
    if "horizontal" in d:
        w = _sub(where, "horizontal")
        out["horizontal"] = _level(d["horizontal"], _HORIZONTAL, w, notes,
                                   plain=("force_measured",))
        if "force_measured" in d["horizontal"]:
            fm = d["horizontal"]["force_measured"]
            if fm not in FORCE_MEASURED:
                raise VtableError(f"{w}.force_measured: expected one of "
                                  f"{', '.join(map(repr, FORCE_MEASURED))}, got {fm!r}")
            out["horizontal"]["force_measured"] = fm
    if "controller" in d:
        c = d["controller"]
        w = _sub(where, "controller")
        if isinstance(c, dict) and "kind" in c and c["kind"] not in kinds.names():
            raise VtableError(f"{w}.kind: expected one of {', '.join(kinds.names())}, got "
                              f"{c['kind']!r} (a lab's own kind: --controller-from FILE)")
        kind = kinds.get(c["kind"]) if isinstance(c, dict) and "kind" in c else None
        own = tuple(kind.user_keys) if kind is not None else ()
        ctl = _level({k: v for k, v in c.items() if k not in own} if isinstance(c, dict)
                     else c, _CONTROLLER, w, notes, plain=("kind", "notch"))
        if "kind" in c:
            ctl["kind"] = c["kind"]
        if "notch" in c:
            ctl["notches"] = _notches(c["notch"], f"{w}.notch")
        if own:
            ctl["extra"] = {k: check_number(c[k], f"{w}.{k}", kind.user_keys[k])
                            for k in own if k in c}
        out["controller"] = ctl
    if "limits" in d:
        w = _sub(where, "limits")
        lim = _level(d["limits"], _LIMITS, w, notes, plain=("band_hz",))
        if "band_hz" in d["limits"]:
            lim["band"] = _band(d["limits"]["band_hz"], f"{w}.band_hz")
        out["limits"] = lim
    return out


def _notches(v: Any, where: str) -> tuple[Notch, ...]:
    """[[table.controller.notch]] entries (at most two)."""
    if not isinstance(v, list) or not all(isinstance(x, dict) for x in v):
        raise VtableError(f"{where}: expected a list of tables, each with "
                          f"{', '.join(NOTCH_KEYS)}")
    if len(v) > 2:
        raise VtableError(f"{where}: at most two notches, got {len(v)}")
    out = []
    for k, n in enumerate(v):
        w = f"{where}[{k}]"
        unknown = set(n) - set(NOTCH_KEYS)
        if unknown:
            k0 = sorted(unknown)[0]
            raise VtableError(f"{w}: unknown key {k0!r}{did_you_mean(k0, NOTCH_KEYS)}; "
                              f"expected one of {', '.join(NOTCH_KEYS)}")
        for key in ("frequency_hz", "width_hz"):
            if key not in n:
                raise VtableError(f"{w}: missing key {key!r}")
        f = check_number(n["frequency_hz"], f"{w}.frequency_hz", "Hz")
        b = check_number(n["width_hz"], f"{w}.width_hz", "Hz")
        depth = check_number(n.get("depth_db", 40.0), f"{w}.depth_db", "1")
        on = n.get("on", "error")
        if not (f > 0 and b > 0 and depth >= 0):
            raise VtableError(f"{w}: frequency_hz and width_hz must be > 0, depth_db >= 0")
        if on not in NOTCH_PLACES:
            raise VtableError(f"{w}.on: expected one of {', '.join(map(repr, NOTCH_PLACES))}, "
                              f"got {on!r}")
        out.append(Notch(f, b, depth, on))
    return tuple(out)


def _merge(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    out = dict(base)
    for k, v in over.items():
        out[k] = _merge(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) \
            else v
    return out


def table_from_dict(d: Any, where: str = "[table]") -> TableDescription:
    """Parse and check a [table] table (a preset and/or a description).

    Parameters
    ----------
    d
        The [table] table as TOML gives it.
    where
        Prefix of error messages and notes, e.g. ``"RUN.toml [table]"``.

    Returns
    -------
    TableDescription
        Values in SI; `notes` lists unknown keys (kept in the run's metadata, not used).
    """
    if not isinstance(d, dict):
        raise VtableError(f"{where}: expected a table, got {type(d).__name__}")
    notes: list[str] = []
    base: dict[str, Any] = {}
    preset = None
    if "preset" in d:
        preset = d["preset"]
        if not isinstance(preset, str) or preset not in TABLE_PRESETS:
            raise VtableError(f"{where}.preset: {preset!r} is not a known table; expected one "
                              f"of {', '.join(TABLE_PRESETS)}")
        base = _parse(TABLE_PRESETS[preset](), f"table preset {preset!r}", [])
    own = _parse(d, where, notes)
    if own.get("controller", {}).get("kind", base.get("controller", {}).get("kind")) != \
            base.get("controller", {}).get("kind"):
        base.pop("controller", None)  # another kind of controller replaces the preset's
    vals = _merge(base, own)
    if preset is None and len(vals) == 0:
        notes.append(f"{where}: names no preset and describes nothing")
    ctl = vals.get("controller")
    if ctl is not None:
        if "kind" not in ctl:
            raise VtableError(f"{_sub(where, 'controller')}: missing key 'kind' (expected one of "
                              f"{', '.join(CONTROLLER_KINDS)})")
        kind = kinds.get(ctl["kind"])
        foreign = [k for k in ctl if k not in SHARED_CONTROL + kind.keys + ("extra",)]
        if foreign:
            names = {q.attr: next(iter(q.keys)) for q in _CONTROLLER} | {"notches": "notch"}
            reads = [names.get(k, k) for k in SHARED_CONTROL[1:] + kind.keys]
            raise VtableError(f"{_sub(where, 'controller')}: {names.get(foreign[0])!r} is not "
                              f"a term of a {ctl['kind']} controller (it reads "
                              f"{', '.join(reads + list(kind.user_keys))})")
        if ctl["kind"] == "pid":
            if not any(ctl.get(k) for k in ("p", "i", "d")):
                raise VtableError(f"{_sub(where, 'controller')}: a pid controller needs "
                                  "gains: give p, i_per_s or d_s (at least one > 0)")
    lim = vals.get("limits")
    return TableDescription(
        preset=preset, dofs=vals.get("dofs"), mass=vals.get("mass"),
        pitch_inertia=vals.get("pitch_inertia"), com_height=vals.get("com_height"),
        horizontal=HorizontalActuators(**vals["horizontal"]) if "horizontal" in vals else None,
        controller=ControllerDescription(**ctl) if ctl is not None else None,
        limits=TableLimits(**lim) if lim is not None else None,
        notes=tuple(notes))
