"""Parameter sets of the report's analytical models: the open-loop triple (eq 6.13-6.16),
table + SDOF (Tables 7.1/7.2), hybrid (Tables 8.1/9.1), mechanical (Tables 5.1/9.3) and
the two-directional table with a pitch actuator (eq 8.16).

Frequencies are stored in Hz (f = ω/2π, the report's "f_o = 2πω_o" means ω_o = 2πf_o).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from vtable.errors import VtableError
from vtable.params.base import Params, plain, quantity
from vtable.params.specimen import SDOFSpecimen

#: the names `vtable.params` gives (the package's public ones)
__all__ = [
    "HorizontalSpring", "HybridParams", "MechanicalParams", "OpenLoop", "RockingSpring",
    "StructureRatios", "TableSDOFParams", "TwoDirectionalParams"
]

TWO_PI = 2 * math.pi


def spring_frequency(k: float, c: float, inertia: float) -> tuple[float, float]:
    """Frequency (Hz) and damping ratio of a spring k and dashpot c on a mass or inertia:
    ω² = k/J, ξ = c/(2ωJ) (eqs 8.35-8.36 for the rocking spring, A.8 for the horizontal,
    8.10 for the stabilizers)."""
    w = math.sqrt(k / inertia)
    return w / TWO_PI, c / (2 * w * inertia)


@dataclass(frozen=True)
class OpenLoop(Params):
    """Equivalent open-loop frequency, damping and gain of a servo loop (eq 6.13/6.16)."""

    f_o: float = quantity("Hz", "f_o_hz", minimum=0)
    xi_o: float = quantity("1", "xi_o", minimum=0, exclusive=False)
    k_o: float = quantity("1/s", "k_o_per_s", minimum=0)
    title: str = plain(default="")
    source: str = plain(default="")

    @property
    def omega_o(self) -> float:
        """ω_o = 2π f_o (rad/s)."""
        return TWO_PI * self.f_o


@dataclass(frozen=True)
class RockingSpring(Params):
    """Equivalent rocking spring and dashpot k_θ, c_θ (eqs 8.31-8.33, Table 8.1)."""

    k_theta: float = quantity("lb-in/rad", "k_theta_lb_in_per_rad", minimum=0)
    c_theta: float = quantity("lb-in-s/rad", "c_theta_lb_in_s_per_rad", minimum=0,
                              exclusive=False)
    source: str = plain(default="")


@dataclass(frozen=True)
class HorizontalSpring(Params):
    """Horizontal spring and dashpot of the mechanical model (Table 5.1)."""

    k_h: float = quantity("kip/in", "k_h_kip_per_in", minimum=0)
    c_h: float = quantity("lb-s/in", "c_h_lb_s_per_in", minimum=0, exclusive=False)
    source: str = plain(default="")


@dataclass(frozen=True)
class StructureRatios(Params):
    """SDOF structure in the report's normalised form: f_s, ξ_s, u = m_s/m_t and
    v = m_s h²/I (eqs 7.5, 8.10)."""

    f_s: float = quantity("Hz", "f_s_hz", minimum=0)
    xi_s: float = quantity("1", "xi_s", minimum=0, exclusive=False)
    u: float = quantity("1", "mass_ratio", minimum=0, exclusive=False)
    v: float = quantity("1", "inertia_ratio", default=0.0, minimum=0, exclusive=False)

    @property
    def omega_s(self) -> float:
        return TWO_PI * self.f_s

    @classmethod
    def from_physical(cls, specimen: SDOFSpecimen, table_mass: float,
                      table_inertia: float) -> StructureRatios:
        """u = m_s/m_t (eq 7.5), v = m_s h²/I (eq 8.10)."""
        m = specimen.mass
        return cls(f_s=specimen.frequency, xi_s=specimen.damping, u=m / table_mass,
                   v=m * specimen.height**2 / table_inertia)


class ModelParams(Params):
    """A model's parameter set whose sub-tables are parameter objects of their own
    (`NESTED`: (key, class) pairs), each read with its own checks and its key in messages."""

    NESTED: ClassVar[tuple[tuple[str, type], ...]] = ()

    @classmethod
    def from_dict(cls, d, where=""):
        where = where or cls.__name__
        if not isinstance(d, dict):
            raise VtableError(f"{where}: expected a table")
        d = dict(d)
        for key, sub_cls in cls.NESTED:
            if key in d:
                d[key] = sub_cls.from_dict(d[key], f"{where}.{key}")
        return Params.from_dict.__func__(cls, d, where)


@dataclass(frozen=True)
class TableSDOFParams(ModelParams):
    """Uni-directional table + SDOF structure (eq 7.7; rows of Tables 7.1 and 7.2)."""

    open_loop: OpenLoop = plain()
    structure: StructureRatios = plain()
    title: str = plain(default="")
    source: str = plain(default="")

    NESTED = (("open_loop", OpenLoop), ("structure", StructureRatios))


@dataclass(frozen=True)
class HybridParams(ModelParams):
    """Hybrid model (eq 8.37, Table 9.1): horizontal servo loop, rocking spring-dashpot
    as ω_θ² = k_θ/I (8.35), ξ_θ = c_θ/(2ω_θ I) (8.36)."""

    open_loop: OpenLoop = plain()
    structure: StructureRatios = plain()
    f_theta: float = quantity("Hz", "f_theta_hz", minimum=0)
    xi_theta: float = quantity("1", "xi_theta", minimum=0, exclusive=False)
    title: str = plain(default="")
    source: str = plain(default="")

    NESTED = (("open_loop", OpenLoop), ("structure", StructureRatios))

    @classmethod
    def from_physical(cls, specimen: SDOFSpecimen, table_mass: float, table_inertia: float,
                      open_loop: OpenLoop, rocking: RockingSpring, **kw) -> HybridParams:
        """Table 8.1 style physical values -> Table 9.1 style ratios (eqs 8.10, 8.35, 8.36)."""
        f, xi = spring_frequency(rocking.k_theta, rocking.c_theta, table_inertia)
        return cls(open_loop=open_loop,
                   structure=StructureRatios.from_physical(specimen, table_mass, table_inertia),
                   f_theta=f, xi_theta=xi, **kw)


@dataclass(frozen=True)
class MechanicalParams(ModelParams):
    """Mechanical model (eq A.13, Table 9.3): horizontal and rocking springs/dashpots."""

    structure: StructureRatios = plain()
    f_h: float = quantity("Hz", "f_h_hz", minimum=0)
    xi_h: float = quantity("1", "xi_h", minimum=0, exclusive=False)
    f_theta: float = quantity("Hz", "f_theta_hz", minimum=0)
    xi_theta: float = quantity("1", "xi_theta", minimum=0, exclusive=False)
    title: str = plain(default="")
    source: str = plain(default="")

    NESTED = (("structure", StructureRatios),)

    @classmethod
    def from_physical(cls, specimen: SDOFSpecimen, table_mass: float, table_inertia: float,
                      horizontal: HorizontalSpring, rocking: RockingSpring,
                      **kw) -> MechanicalParams:
        """Table 5.1 style physical values -> Table 9.3 style ratios (eq A.8)."""
        f_h, xi_h = spring_frequency(horizontal.k_h, horizontal.c_h, table_mass)
        f_r, xi_r = spring_frequency(rocking.k_theta, rocking.c_theta, table_inertia)
        return cls(structure=StructureRatios.from_physical(specimen, table_mass, table_inertia),
                   f_h=f_h, xi_h=xi_h, f_theta=f_r, xi_theta=xi_r, **kw)


@dataclass(frozen=True)
class TwoDirectionalParams(ModelParams):
    """Two-directional table (eq 8.16): horizontal loop (f_o, ξ_o, k_o), pitch actuator
    loop (f_r, ξ_r, k_r, eq 8.2) and passive stabilizers ω_p² = k_p/I, ξ_p (eq 8.10)."""

    open_loop: OpenLoop = plain()
    pitch_loop: OpenLoop = plain()
    structure: StructureRatios = plain()
    f_p: float = quantity("Hz", "f_p_hz", minimum=0, exclusive=False)
    xi_p: float = quantity("1", "xi_p", minimum=0, exclusive=False)
    height: float = quantity("in", "height_in", minimum=0, doc="h of x_r = θh")
    title: str = plain(default="")
    source: str = plain(default="")

    NESTED = (("open_loop", OpenLoop), ("pitch_loop", OpenLoop), ("structure", StructureRatios))
