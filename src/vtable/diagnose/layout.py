"""The vector of parameters a `TableModel` fits: every calibrated base parameter
(`vtable.diagnose.calibration.base_params`) and every continuous parameter of the model's
effects, on their fitted scale (the logarithm for log parameters), packed into and out of
a `Physics`, with the calibration's priors on them."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from vtable.diagnose.calibration import BaseParam, base_params, specimen_params
from vtable.diagnose.campaign import Campaign
from vtable.effects.registry import get as effect
from vtable.errors import VtableError
from vtable.models.physics import Physics
from vtable.models.reduced import ReducedAssembly


def _effect_param(name: str, p) -> BaseParam:
    def get(ph: Physics) -> float:
        return float(ph.effects[name][p.name])

    def put(ph: Physics, v: float) -> Physics:
        eff = {k: dict(val) for k, val in ph.effects.items()}
        eff[name][p.name] = v
        return dataclasses.replace(ph, effects=eff)

    return BaseParam(f"{name}.{p.name}", p.unit, float(p.default), p.lower, p.upper, p.log,
                     None, f"effect:{name}", get, put)


def pitches(ph: Physics, vt) -> bool:
    """Whether the model `ph` lets the platen pitch on table `vt`."""
    try:
        m = ReducedAssembly(ph, vt)
        ph.apply(m, "reduced")
    except VtableError:
        return False
    return "pitch" in m.active


def with_states(ph: Physics, campaign: Campaign) -> Physics:
    """`ph` with a specimen for each further state of `campaign` (its own where `ph` has
    one, else the state's declared one); none when the campaign has one state."""
    extra = campaign.state_specimens
    base = next(iter(campaign.states), None)
    if set(ph.states) == set(extra) and ph.base_state == base:
        return ph
    return dataclasses.replace(ph, states={s: ph.states.get(s, spec)
                                           for s, spec in extra.items()}, base_state=base)


def state_params(state: str, declared, cal) -> list[BaseParam]:
    """The specimen's calibrated parameters in a further state of the campaign (its runs'
    declaration, the same bounds and priors): keys "specimen[STATE].param", read from and
    written to `Physics.states[STATE]`."""
    out = []
    for p in specimen_params(declared, cal):
        def get(ph: Physics, p=p) -> float:
            return p.get(ph.in_state(state))

        def put(ph: Physics, v: float, p=p) -> Physics:
            spec = p.set(ph.in_state(state), v).specimen
            return dataclasses.replace(ph, states={**ph.states, state: spec})

        key = p.key.replace("specimen.", f"specimen[{state}].", 1)
        out.append(dataclasses.replace(p, key=key, get=get, set=put))
    return out


class Layout:
    """`TableModel`'s parameter vector (the module docstring); it provides `declared`,
    `vt`, `calibration` and `_last`."""

    def base_params(self, ph: Physics) -> list[BaseParam]:
        """Every calibrated base parameter of `ph` on this campaign's table, and the
        specimen's again for each further state of the campaign (`state_params`)."""
        out = base_params(self.declared if self.declared is not None else ph.specimen,
                          self.vt, self.calibration, pitch=pitches(ph, self.vt))
        for state, spec in getattr(self, "state_specimens", {}).items():
            out += state_params(state, spec, self.calibration)
        return out

    def _layout(self, ph: Physics) -> list[BaseParam]:
        """The fitted parameters: the base's and the effects' continuous ones (a discrete
        parameter is chosen by `_fit`, not moved by least squares)."""
        return self.base_params(ph) + [_effect_param(name, p) for name in ph.effects
                                       for p in effect(name).params if not p.discrete]

    @staticmethod
    def _pack(ph: Physics, lay) -> np.ndarray:
        return np.array([math.log(p.get(ph)) if p.log else p.get(ph) for p in lay])

    @staticmethod
    def _set(ph: Physics, p: BaseParam, xi: float) -> Physics:
        """`ph` with parameter `p` at `xi` on its fitted scale (clipped to its bounds)."""
        v = math.exp(xi) if p.log else float(xi)
        return p.set(ph, float(min(max(v, p.lower), p.upper)))  # np.clip, without its cost

    @classmethod
    def _unpack(cls, x: np.ndarray, ph: Physics, lay) -> Physics:
        """`ph` with every parameter of `lay` at `x`. One at a time, a parameter can meet
        a state the others have not reached yet (a Rayleigh building's mode damping computed
        with the new frequencies and the old masses: no shear building has them); such a
        parameter is set again once the others are."""
        later = []
        for xi, p in zip(x, lay, strict=True):
            try:
                ph = cls._set(ph, p, xi)
            except VtableError:
                later.append((xi, p))
        for xi, p in later:
            ph = cls._set(ph, p, xi)
        return ph

    def _unpack_fast(self, x: np.ndarray, start: Physics, lay) -> Physics:
        """`_unpack`, from the last vector unpacked on the same start and layout when there
        is one: only the parameters that differ are set again (a finite-difference Jacobian
        moves one at a time; each is set independently of the others)."""
        last = self._last
        if last is not None and last[0] is start and last[1] is lay:
            ph = last[3]
            for i in np.flatnonzero(x != last[2]):
                ph = self._set(ph, lay[i], x[i])
        else:
            ph = self._unpack(x, start, lay)
        self._last = (start, lay, x.copy(), ph)
        return ph

    def _priors(self, x: np.ndarray, lay, campaign: Campaign) -> np.ndarray:
        lam = self.calibration.prior_weight * campaign.floor * math.sqrt(len(campaign.targets))
        out = [lam * (xi - (math.log(p.declared) if p.log else p.declared)) / p.prior
               for xi, p in zip(x, lay, strict=True) if p.prior]
        return np.array(out)

    @staticmethod
    def bounds(lay) -> tuple[np.ndarray, np.ndarray]:
        """The layout's bounds on the fitted scale (the logarithm for log parameters)."""
        return (np.array([math.log(p.lower) if p.log else p.lower for p in lay]),
                np.array([math.log(p.upper) if p.log else p.upper for p in lay]))

