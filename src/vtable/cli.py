"""The ``vtable`` command line: demo, modes, tf, margins, presets."""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any

import numpy as np

from vtable import __version__
from vtable.errors import UnstableError, VtableError


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, no usage dump
        raise VtableError(f"{message} (see vtable {self.prog.split()[-1]} --help)"
                          if " " in self.prog else f"{message} (see vtable --help)")


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog="vtable", description="Virtual shaking table after UCB/EERC-91/13.")
    p.add_argument("--version", action="version", version=f"vtable {__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    def config_cmd(name: str, help: str) -> argparse.ArgumentParser:
        c = sub.add_parser(name, help=help, description=help)
        c.add_argument("config", nargs="?", default="eerc-sdof",
                       help="a named configuration (vtable presets) or a model .toml file "
                            "[default: eerc-sdof]")
        c.add_argument("--json", action="store_true", help="machine-readable output")
        return c

    d = sub.add_parser("demo", help="the built-in EERC configuration: coupled modes, margins")
    d.add_argument("--json", action="store_true")
    config_cmd("modes", "eigen-modes: frequency, damping and real roots (eqs 9.1-9.4)")
    m = config_cmd("margins", "gain and phase margins of L = H/(1-H), H = x_t/x_c")
    m.add_argument("--out", default="x_t", help="tracked output [x_t]")
    m.add_argument("--in", dest="inp", default="x_c", help="command input [x_c]")
    t = config_cmd("tf", "frequency response of one output over one input")
    t.add_argument("--out", default="x_t", help="output [x_t]")
    t.add_argument("--in", dest="inp", default="x_c", help="input [x_c]")
    t.add_argument("--fmin", type=float, default=0.5, help="lowest frequency, Hz [0.5]")
    t.add_argument("--fmax", type=float, default=20.0, help="highest frequency, Hz [20]")
    t.add_argument("--n", type=int, default=40, help="number of frequencies [40]")
    t.add_argument("--log", action="store_true", help="log-spaced frequencies")
    pr = sub.add_parser("presets", help="list the named configurations")
    pr.add_argument("--json", action="store_true")
    return p


# ---- commands ---------------------------------------------------------------------------
def _modes_dict(model) -> dict[str, Any]:
    m = model.modes()
    return {"model": model.title, "stable": model.is_stable(),
            "modes": [{"f_hz": x.f_hz, "damping": x.damping} for x in m.oscillatory],
            "real_roots_per_s": list(m.real_roots)}


def _margins_dict(model, out: str, inp: str) -> dict[str, Any]:
    g = model.margins(out, inp)
    return {"model": model.title, "loop": f"L = H/(1-H), H = {out}/{inp}",
            "gain_margin": g.gain_margin, "phase_margin_deg": g.phase_margin,
            "f_phase_crossover_hz": g.f_phase_crossover, "f_gain_crossover_hz": g.f_gain_crossover}


def _print_modes(d: dict[str, Any]) -> None:
    print(f"{d['model']}: {'stable' if d['stable'] else 'UNSTABLE'}")
    print(f"  {'mode':>4}  {'f (Hz)':>9}  {'damping':>8}")
    for i, m in enumerate(d["modes"], 1):
        print(f"  {i:>4}  {m['f_hz']:9.4f}  {m['damping']:8.4f}")
    if d["real_roots_per_s"]:
        print("  real roots (1/s): " + ", ".join(f"{r:.2f}" for r in d["real_roots_per_s"]))


def _print_margins(d: dict[str, Any]) -> None:
    print(f"{d['model']}: {d['loop']}")
    print(f"  gain margin  {d['gain_margin']:.3f}   at {d['f_phase_crossover_hz']:.3f} Hz")
    print(f"  phase margin {d['phase_margin_deg']:.2f} deg at {d['f_gain_crossover_hz']:.3f} Hz")


def cmd_modes(a: argparse.Namespace) -> dict[str, Any]:
    from vtable.analytic import configs

    model = configs.load(a.config)
    model.check_stable()
    return _modes_dict(model)


def cmd_margins(a: argparse.Namespace) -> dict[str, Any]:
    from vtable.analytic import configs

    return _margins_dict(configs.load(a.config), a.out, a.inp)


def cmd_tf(a: argparse.Namespace) -> dict[str, Any]:
    from vtable.analytic import configs

    if not (0 < a.fmin < a.fmax):
        raise VtableError(f"need 0 < --fmin < --fmax, got {a.fmin:g}, {a.fmax:g}")
    if a.n < 2:
        raise VtableError(f"--n must be at least 2, got {a.n}")
    model = configs.load(a.config)
    model.check_stable()
    f = (np.geomspace if a.log else np.linspace)(a.fmin, a.fmax, a.n)
    H = model.freqresp(f, a.out, a.inp)
    return {"model": model.title, "output": a.out, "input": a.inp, "f_hz": f.tolist(),
            "magnitude": np.abs(H).tolist(), "phase_deg": np.degrees(np.angle(H)).tolist()}


def _print_tf(d: dict[str, Any]) -> None:
    print(f"{d['model']}: {d['output']}/{d['input']}")
    print(f"  {'f (Hz)':>9}  {'|H|':>10}  {'phase (deg)':>11}")
    for f, m, p in zip(d["f_hz"], d["magnitude"], d["phase_deg"], strict=True):
        print(f"  {f:9.3f}  {m:10.4g}  {p:11.2f}")


def cmd_demo(a: argparse.Namespace) -> dict[str, Any]:
    from vtable.analytic import configs

    model = configs.load(configs.DEFAULT)
    model.check_stable()
    f = np.linspace(0.2, 15.0, 2961)
    xt, xe = np.abs(model.freqresp(f, "x_t", "x_c")), np.abs(model.freqresp(f, "x_eff", "x_c"))
    th = np.abs(model.freqresp(f, "theta_h", "x_c"))
    near = f < 5.0
    return {"configuration": configs.DEFAULT, **_modes_dict(model),
            "margins": _margins_dict(model, "x_t", "x_c"),
            "x_t/x_c": {"peak": float(xt[near].max()),
                        "f_peak_hz": float(f[near][xt[near].argmax()]),
                        "notch": float(xt[near].min()),
                        "f_notch_hz": float(f[near][xt[near].argmin()])},
            "x_eff/x_c notch_hz": float(f[near][xe[near].argmin()]),
            "theta_h/x_c peak_hz": float(f[near][th[near].argmax()])}


def _print_demo(d: dict[str, Any]) -> None:
    print("vtable demo: the SDOF braced frame (68 kips, 219 in) on the EERC table")
    print("hybrid model, report Table 9.1 (horizontal servo loop + rocking spring/dashpot)\n")
    _print_modes(d)
    print()
    _print_margins(d["margins"])
    p = d["x_t/x_c"]
    print(f"\ntable motion x_t/x_c: peak {p['peak']:.2f} at {p['f_peak_hz']:.2f} Hz, "
          f"notch {p['notch']:.2f} at {p['f_notch_hz']:.2f} Hz")
    print(f"effective motion (x_t + θh)/x_c: notch at {d['x_eff/x_c notch_hz']:.2f} Hz "
          f"(fixed-base 2.87 Hz); pitch θh/x_c peaks at {d['theta_h/x_c peak_hz']:.2f} Hz")


def cmd_presets(a: argparse.Namespace) -> dict[str, Any]:
    from vtable.analytic import configs

    return {"configurations": configs.names()}


_COMMANDS = {
    "demo": (cmd_demo, _print_demo),
    "modes": (cmd_modes, _print_modes),
    "margins": (cmd_margins, _print_margins),
    "tf": (cmd_tf, _print_tf),
    "presets": (cmd_presets, lambda d: print("\n".join(d["configurations"]))),
}


def _jsonable(x: Any) -> Any:
    if isinstance(x, dict):
        return {k: _jsonable(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_jsonable(v) for v in x]
    if isinstance(x, float | np.floating):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer | np.bool_):
        return x.item()
    return x


def main(argv: list[str] | None = None) -> int:
    try:
        a = _parser().parse_args(argv)
        run, show = _COMMANDS[a.command]
        result = run(a)
        if a.json:
            print(json.dumps(_jsonable(result), indent=2))
        else:
            show(result)
        return 0
    except UnstableError as e:
        print(f"vtable: {e}", file=sys.stderr)
        return 3
    except VtableError as e:
        print(f"vtable: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
