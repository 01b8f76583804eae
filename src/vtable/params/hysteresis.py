"""Hysteretic storeys: the Bouc–Wen declaration of a specimen's yielding storeys
(`[specimen.hysteresis]` of the run format, docs/run-format.md).

A hysteretic storey of elastic stiffness k (the storey's, from the declared frequencies)
resists its drift u with

    V = α k u + (1 − α) k u_y z,
    ż = (u̇ − β |u̇| |z|^(n−1) z − γ u̇ |z|^n) / u_y                  (Bouc–Wen)

(Wen 1976, J. Eng. Mech. Div. ASCE 102(2):249–263, with A = 1; Baber & Wen 1981, J. Eng.
Mech. Div. ASCE 107(6):1069–1087): u_y the yield drift, α the post-yield stiffness ratio,
n the sharpness of the elastic-to-plastic transition (large n: bilinear), β and γ the
shape of the loops (β + γ = 1 keeps |z| ≤ 1, so the storey's strength is
α k u + (1 − α) k u_y; β = γ = 0.5 is the usual choice, Baber & Wen 1981). The report
treats the fixed-base parameters as amplitude-dependent (ch. 3, §5.3's loops); the
analytical models use the initial stiffness k (`specimen_hints` says so).

The declaration names the storeys that yield (`storeys`, 1-based from the bottom; all
of them when left out) and, for each, u_y (`yield_drift_in`, or `yield_shear_kip`: the
strength V_y = k u_y, kept as declared and turned into u_y with the storey's stiffness as
the model carries it) and α (`post_yield_ratio`); a single number applies to every listed
storey. `n`, `beta`, `gamma` are shared."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from vtable.errors import VtableError, did_you_mean
from vtable.params.base import Params, check_number, plain, quantity, respelled

KEYS = ("storeys", "yield_drift_in", "yield_shear_kip", "post_yield_ratio", "n", "beta",
        "gamma")
#: the keys in other units (`params.base.respelled`)
SPELLINGS = {"yield_drift_in": ("in", {"yield_drift_m": "m", "yield_drift_mm": "mm"}, None),
             "yield_shear_kip": ("kip", {"yield_shear_n": "N", "yield_shear_kn": "kN"}, None)}
#: the usual shape: β = γ = 0.5 (Baber & Wen 1981), n = 2 (a smooth knee)
DEFAULT_N, DEFAULT_BETA, DEFAULT_GAMMA = 2.0, 0.5, 0.5


@dataclass(frozen=True)
class Hysteresis(Params):
    """Bouc–Wen storeys (module docstring): `storeys` 1-based, and per listed storey its
    yield drift u_y (m) and post-yield ratio α; shared n, β, γ."""

    storeys: tuple[int, ...] = plain()
    post_yield_ratio: tuple[float, ...] = quantity("1", "post_yield_ratio", vector=True,
                                                   minimum=0, exclusive=False, maximum=1,
                                                   doc="α of each listed storey")
    yield_drift: tuple[float, ...] | None = quantity(
        "in", "yield_drift_in", default=None, vector=True, minimum=0,
        doc="u_y of each listed storey")
    yield_shear: tuple[float, ...] | None = quantity(
        "kip", "yield_shear_kip", default=None, vector=True, minimum=0,
        doc="V_y = k u_y of each listed storey (instead of u_y)")
    n: float = quantity("1", "n", default=DEFAULT_N, minimum=1, exclusive=False,
                        maximum=50, source="Baber & Wen 1981: n = 2, a smooth knee",
                        doc="sharpness of the transition")
    beta: float = quantity("1", "beta", default=DEFAULT_BETA, minimum=0, exclusive=False,
                           source="Baber & Wen 1981: 0.5")
    gamma: float = quantity("1", "gamma", default=DEFAULT_GAMMA, source="Baber & Wen 1981: 0.5")

    def __post_init__(self) -> None:
        super().__post_init__()
        where = "hysteresis"
        if len(set(self.storeys)) != len(self.storeys) or not self.storeys:
            raise VtableError(f"{where}.storeys: expected distinct storey numbers, got "
                              f"{list(self.storeys)}")
        if (self.yield_drift is None) == (self.yield_shear is None):
            raise VtableError(f"{where}: give exactly one of yield_drift_in and "
                              "yield_shear_kip")
        for key, v in (("yield_drift_in", self.yield_drift),
                       ("yield_shear_kip", self.yield_shear),
                       ("post_yield_ratio", self.post_yield_ratio)):
            if v is not None and len(v) != len(self.storeys):
                raise VtableError(f"{where}.{key}: {len(v)} values for {len(self.storeys)} "
                                  "storeys")
        if not self.beta + self.gamma > 0:
            raise VtableError(f"{where}: beta + gamma must be > 0 (the loops' strength is "
                              f"finite only then), got {self.beta:g} + {self.gamma:g}")

    def of_storey(self, k: int, stiffness: float) -> tuple[float, float] | None:
        """(u_y in m, α) of storey k (1-based) whose elastic stiffness is `stiffness`
        (N/m; a declared strength gives u_y = V_y/k), None when it stays elastic."""
        if k not in self.storeys:
            return None
        i = self.storeys.index(k)
        u_y = self.yield_drift[i] if self.yield_drift is not None else \
            self.yield_shear[i] / stiffness
        return u_y, self.post_yield_ratio[i]

    @property
    def z_max(self) -> float:
        """The largest |z| the loops reach: (1/(β + γ))^(1/n) (1 when β + γ = 1)."""
        return (1.0 / (self.beta + self.gamma)) ** (1.0 / self.n)

    def to_dict(self) -> dict[str, Any]:
        d = super().to_dict()
        d["storeys"] = list(self.storeys)
        return d


def parse_hysteresis(d: Any, n_storeys: int, where: str) -> Hysteresis:
    """The `[specimen.hysteresis]` table of a specimen of `n_storeys` storeys."""
    if not isinstance(d, dict):
        raise VtableError(f"{where}: expected a table, got {type(d).__name__}")
    d = respelled(d, SPELLINGS, where)
    unknown = sorted(set(d) - set(KEYS))
    if unknown:
        raise VtableError(f"{where}: unknown key {unknown[0]!r}"
                          f"{did_you_mean(unknown[0], KEYS)}; expected {', '.join(KEYS)}")
    storeys = d.get("storeys", list(range(1, n_storeys + 1)))
    if not isinstance(storeys, list) or not storeys or any(
            isinstance(s, bool) or not isinstance(s, int) or not 1 <= s <= n_storeys
            for s in storeys):
        raise VtableError(f"{where}.storeys: expected a list of storey numbers "
                          f"1..{n_storeys}, got {storeys!r:.60}")
    if ("yield_drift_in" in d) == ("yield_shear_kip" in d):
        raise VtableError(f"{where}: give exactly one of yield_drift_in and yield_shear_kip")
    if "post_yield_ratio" not in d:
        raise VtableError(f"{where}: missing key 'post_yield_ratio' (α, the post-yield "
                          "stiffness over the elastic one)")
    out: dict[str, Any] = {"storeys": tuple(storeys)}
    for key, field_name in (("yield_drift_in", "yield_drift"), ("yield_shear_kip", "yield_shear"),
                            ("post_yield_ratio", "post_yield_ratio")):
        if key not in d:
            continue
        v = d[key]
        vals = v if isinstance(v, list) else [v] * len(storeys)
        if len(vals) != len(storeys):
            raise VtableError(f"{where}.{key}: {len(vals)} values for {len(storeys)} storeys "
                              f"({list(storeys)})")
        unit = {"yield_drift_in": "in", "yield_shear_kip": "kip"}.get(key, "1")
        out[field_name] = tuple(check_number(x, f"{where}.{key}[{i}]", unit)
                                for i, x in enumerate(vals))
        if key != "post_yield_ratio" and any(not (math.isfinite(x) and x > 0)
                                             for x in out[field_name]):
            raise VtableError(f"{where}.{key}: every value must be > 0")
    out.update({k: check_number(d[k], f"{where}.{k}") for k in ("n", "beta", "gamma") if k in d})
    try:
        return Hysteresis(**out)
    except VtableError as e:
        raise VtableError(f"{where}: {e}") from None
