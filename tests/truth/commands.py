"""Table displacement commands: band-limited random, earthquake (El Centro 1940 NS or a
synthetic Kanai-Tajimi record), sine. Sampled finely (2 kHz) and interpolated linearly by
the integrator; they start and end at rest."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy import signal

from .constants import INCH, G
from .errors import TruthError

FS_CMD = 2000.0  # Hz
RECORDS = Path(__file__).resolve().parents[2] / "assets" / "records"


@dataclass(frozen=True)
class Command:
    """x (m) at t (s, uniform from 0); `table` is the run format's [command] table."""

    t: np.ndarray
    x: np.ndarray
    title: str
    table: dict = field(default_factory=dict)

    @property
    def duration(self) -> float:
        return float(self.t[-1])

    def at(self, tq: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Command displacement and velocity at times tq (linear interpolation)."""
        v = np.gradient(self.x, self.t)
        return np.interp(tq, self.t, self.x), np.interp(tq, self.t, v)

    def acceleration(self, tq: np.ndarray) -> np.ndarray:
        """Command acceleration at times tq (second difference, linear interpolation): what
        an acceleration feedforward without a reference generator uses."""
        a = np.gradient(np.gradient(self.x, self.t), self.t)
        return np.interp(tq, self.t, a)


def _grid(duration_s: float, fs: float) -> np.ndarray:
    if not duration_s > 0:
        raise TruthError(f"command: duration_s must be positive, got {duration_s!r}")
    return np.arange(round(duration_s * fs) + 1) / fs


def _ends(t: np.ndarray, taper_s: float) -> np.ndarray:
    """A window that rises as sin² over taper_s from 0 and falls back at the end (zero value
    and slope at both ends, so the command starts and ends at rest)."""
    w = np.ones_like(t)
    if taper_s > 0:
        T = t[-1]
        r = np.clip(t / taper_s, 0, 1)
        f = np.clip((T - t) / taper_s, 0, 1)
        w = np.sin(0.5 * np.pi * r) ** 2 * np.sin(0.5 * np.pi * f) ** 2
    return w


def _scale(x: np.ndarray, peak_in: float | None, rms_in: float | None) -> np.ndarray:
    if (peak_in is None) == (rms_in is None):
        raise TruthError("command: give exactly one of peak_in or rms_in")
    if peak_in is not None:
        return x * (peak_in * INCH / np.max(np.abs(x)))
    return x * (rms_in * INCH / np.sqrt(np.mean(x**2)))


def random_command(duration_s: float, band_hz: tuple[float, float] = (0.0, 25.0),
                   peak_in: float | None = None, rms_in: float | None = None, seed: int = 0,
                   pink: bool = False, taper_s: float = 0.5, fs: float = FS_CMD) -> Command:
    """Filtered Gaussian noise: random complex spectrum kept inside `band_hz` (displacement
    PSD flat, or ∝ 1/f when `pink`), tapered at the ends, scaled to a peak or rms (in).
    The lowest frequency is at least 2/duration (no drift)."""
    lo, hi = (float(b) for b in band_hz)
    if not 0 <= lo < hi:
        raise TruthError(f"command: band_hz must be (lo, hi) with 0 <= lo < hi, got {band_hz}")
    t = _grid(duration_s, fs)
    rng = np.random.default_rng(seed)
    f = np.fft.rfftfreq(len(t), 1 / fs)
    spec = rng.standard_normal(len(f)) + 1j * rng.standard_normal(len(f))
    keep = (f >= max(lo, 2.0 / duration_s)) & (f <= hi)
    spec[~keep] = 0
    if pink:
        spec[keep] /= np.sqrt(f[keep])
    x = np.fft.irfft(spec, len(t)) * _ends(t, taper_s)
    table = {"kind": "random", "band_hz": [lo, hi]}
    title = f"{'pink ' if pink else ''}random {lo:g}-{hi:g} Hz"
    return Command(t, _scale(x, peak_in, rms_in), title, table)


def sine_command(freq_hz: float, amp_in: float, duration_s: float, ramp_s: float = 1.0,
                 fs: float = FS_CMD) -> Command:
    """A sine of amplitude amp_in (in), ramped in and out over ramp_s."""
    t = _grid(duration_s, fs)
    x = amp_in * INCH * np.sin(2 * np.pi * freq_hz * t) * _ends(t, ramp_s)
    return Command(t, x, f"sine {freq_hz:g} Hz", {"kind": "sine", "band_hz": [freq_hz,
                                                                             freq_hz]})


def _read_record(name: str) -> tuple[np.ndarray, np.ndarray, str]:
    if name != "elcentro":
        raise TruthError(f"command: unknown record {name!r}; known: elcentro, synthetic")
    path = RECORDS / "elcentro_1940_ns.csv"
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    return data[:, 0], data[:, 1] * G, "El Centro 1940 NS"


def _kanai_tajimi(seed: int, duration_s: float = 25.0, dt: float = 0.01,
                  f_g: float = 2.5, xi_g: float = 0.6) -> tuple[np.ndarray, np.ndarray]:
    """Ground acceleration: white noise through the Kanai-Tajimi filter
    (2ξ_g ω_g s + ω_g²)/(s² + 2ξ_g ω_g s + ω_g²), times a rise-hold-decay envelope."""
    rng = np.random.default_rng(seed)
    t = np.arange(round(duration_s / dt) + 1) * dt
    wg = 2 * np.pi * f_g
    sys = signal.lti([2 * xi_g * wg, wg**2], [1, 2 * xi_g * wg, wg**2])
    _, a, _ = signal.lsim(sys, rng.standard_normal(len(t)), t)
    env = np.where(t < 2.0, (t / 2.0) ** 2, np.where(t < 10.0, 1.0, np.exp(-0.3 * (t - 10.0))))
    return t, a * env


def earthquake_command(record: str = "elcentro", peak_in: float = 4.0,
                       time_scale: float = 1.811, band_hz: tuple[float, float] = (0.2, 25.0),
                       seed: int = 0, lead_s: float = 1.0, tail_s: float = 3.0,
                       fs: float = FS_CMD) -> Command:
    """An accelerogram made into a table displacement command (cf. report §9.2):
    time-compressed by `time_scale` (§9.2: length scale 3.2801 -> time scale 1.811),
    integrated twice in the frequency domain with cosine band edges at band_hz (0.5-1x the
    low edge, 0.9-1x the high edge), padded with `lead_s` and `tail_s` of rest, windowed
    (sin² over the pads) so displacement and velocity start and end at zero, and scaled to
    a peak displacement of `peak_in` inches."""
    if record == "synthetic":
        tr, ar = _kanai_tajimi(seed)
        title = f"synthetic Kanai-Tajimi record (seed {seed})"
    else:
        tr, ar, title = _read_record(record)
    if not time_scale > 0:
        raise TruthError(f"command: time_scale must be positive, got {time_scale!r}")
    dt = (tr[1] - tr[0]) / time_scale
    n0 = round(lead_s / dt)
    n1 = round(tail_s / dt)
    # amplitude is irrelevant: the displacement is scaled to peak_in at the end
    a = np.concatenate([np.zeros(n0), ar, np.zeros(n1)])
    nfft = 1 << math.ceil(math.log2(4 * len(a)))
    f = np.fft.rfftfreq(nfft, dt)
    lo, hi = band_hz
    h = np.ones_like(f)
    h[f <= 0.5 * lo] = 0
    ramp = (f > 0.5 * lo) & (f < lo)
    h[ramp] = np.sin(0.5 * np.pi * (f[ramp] - 0.5 * lo) / (0.5 * lo)) ** 2
    top = (f > 0.9 * hi) & (f < hi)
    h[top] = np.cos(0.5 * np.pi * (f[top] - 0.9 * hi) / (0.1 * hi)) ** 2
    h[f >= hi] = 0
    w = 2 * np.pi * np.where(f > 0, f, 1.0)
    D = -np.fft.rfft(a, nfft) * h / w**2
    D[0] = 0
    d = np.fft.irfft(D, nfft)[: len(a)]
    td = np.arange(len(a)) * dt
    T = td[-1]
    win = np.ones_like(td)
    r = td < lead_s
    win[r] = np.sin(0.5 * np.pi * td[r] / lead_s) ** 2
    e = td > T - tail_s
    win[e] = np.sin(0.5 * np.pi * (T - td[e]) / tail_s) ** 2
    d = d * win
    t = _grid(T, fs)
    from scipy.interpolate import CubicSpline

    x = CubicSpline(td, d, bc_type="clamped")(t)
    x = _scale(x, peak_in, None)
    table = {"kind": "earthquake", "band_hz": [float(lo), float(hi)]}
    return Command(t, x, f"{title}, time scale {time_scale:g}", table)
