"""The analytical models' verbs: eigen-modes, margins and the frequency response of a
named configuration or a model file, and the list of named configurations."""

from __future__ import annotations

from typing import Any

import numpy as np

from vtable.analytic import configs
from vtable.errors import VtableError
from vtable.results import FrequencyResponse, MarginsResult, ModesResult, Presets


def modes_dict(model) -> dict[str, Any]:
    """A model's oscillatory modes and real roots (eqs 9.1-9.4), as `ModesResult` takes them."""
    m = model.modes()
    return {"model": model.title, "stable": model.is_stable(),
            "modes": [{"f_hz": x.f_hz, "damping": x.damping} for x in m.oscillatory],
            "real_roots_per_s": list(m.real_roots)}


def margins_dict(model, out: str, inp: str) -> dict[str, Any]:
    """A model's gain and phase margins of L = H/(1-H), H = out/inp, as `MarginsResult` takes
    them."""
    g = model.margins(out, inp)
    return {"model": model.title, "loop": f"L = H/(1-H), H = {out}/{inp}",
            "gain_margin": g.gain_margin, "phase_margin_deg": g.phase_margin,
            "f_phase_crossover_hz": g.f_phase_crossover, "f_gain_crossover_hz": g.f_gain_crossover}


def modes(config: str) -> ModesResult:
    """Eigen-modes of a named configuration or a model file (eqs 9.1-9.4)."""
    model = configs.load(config)
    model.check_stable()
    return ModesResult(**modes_dict(model))


def margins(config: str, out: str = "x_t", inp: str = "x_c") -> MarginsResult:
    """Gain and phase margins of L = H/(1-H), H = out/inp."""
    return MarginsResult(**margins_dict(configs.load(config), out, inp))


def presets() -> Presets:
    """The named configurations."""
    return Presets(configs.names())


def config_tf(config: str, out: str = "x_t", inp: str = "x_c", fmin: float = 0.5,
              fmax: float = 20.0, n: int = 40, log: bool = False,
              png: str | None = None) -> FrequencyResponse:
    """The frequency response out/inp of a model (a named configuration or a model file)
    at `n` frequencies from `fmin` to `fmax` (log-spaced if `log`), plotted to `png`."""
    if not (0 < fmin < fmax):
        raise VtableError(f"need 0 < --fmin < --fmax, got {fmin:g}, {fmax:g}")
    if n < 2:
        raise VtableError(f"--n must be at least 2, got {n}")
    model = configs.load(config)
    model.check_stable()
    f = (np.geomspace if log else np.linspace)(fmin, fmax, n)
    H = model.freqresp(f, out, inp)
    r = FrequencyResponse(model.title, out, inp, f, H, f"{model.title}: {out}/{inp}")
    if png:
        r.plot(png)
    return r
