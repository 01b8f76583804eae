"""Matplotlib figures (PNG): transfer functions with coherence, response spectra and
coupled-mode sweeps."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from vtable.fileio import atomic_path
from vtable.signals.content import CONTENT_POWER

plt.switch_backend("Agg")  # figures are written to files: no window, whatever the default


def magnitude_band(H: np.ndarray, coherence: np.ndarray, averages: int) -> np.ndarray:
    """The normalised random error of |H1|, sqrt(1 − γ²)/(|γ| sqrt(2 n_d)) (Bendat &
    Piersol, *Random Data*, eq 9.90): the measured magnitude's ±1 standard deviation is
    |H|(1 ± ε)."""
    g = np.sqrt(np.clip(coherence, 1e-6, 1.0))
    return np.sqrt(1 - g**2) / (g * np.sqrt(2 * averages))


#: the measured H1 is drawn only where its coherence is at least this (`supported`): below
#: it, more than half of the output's power at that line is not linearly related to the
#: command (noise, nonlinearity, leakage), so the ratio shows that, not the transfer function
COHERENCE_MIN = 0.5
#: ... and where the command's power spectral density is at least this fraction of its peak
#: (within 40 dB of it: an earthquake's displacement command falls steeply with frequency
#: and stays coherent well below its peak; at 60 dB a band-limited random one's leakage
#: beyond its band passed): beyond the command's band H1 divides noise by almost nothing, and
#: with the few averages of a short run (3) noise alone passes γ² ≥ 0.5 on a quarter of the
#: lines ((1 − 0.5)^(n_d − 1), Carter, Knapp & Nuttall 1973), so coherence alone cannot
#: reject them
COMMAND_POWER_MIN = CONTENT_POWER  # 40 dB (vtable.signals.content)
#: the figures' width (in) and the report's resolution (dpi): 1200 px, a page's width
WIDTH_IN = 10.0
#: legend and axis-label font sizes (pt): 16-18 px at 120 dpi, shown at the page's width
LEGEND_FONTSIZE = 11
LABEL_FONTSIZE = 12
TICK_FONTSIZE = 11
#: the models' lines: wide and translucent beneath the measured trace (thin, black, on
#: top), so that both show where they agree
MODEL_LW, MEASURED_LW, MODEL_ALPHA = 2.8, 1.0, 0.75
MODEL_Z, MEASURED_Z = 2, 4


def supported(coherence, command_psd=None, min_coherence: float = COHERENCE_MIN,
              min_power: float = COMMAND_POWER_MIN) -> np.ndarray:
    """Where a measured transfer function is drawn: coherence γ² ≥ `min_coherence` and,
    with the command's power spectral density, that at least `min_power` x its peak."""
    keep = np.asarray(coherence) >= min_coherence
    if command_psd is not None:
        g = np.asarray(command_psd, float)
        keep &= g >= min_power * float(np.max(g, initial=0.0))
    return keep


def style_axes(*axes) -> None:
    """Readable tick labels and axis labels (`TICK_FONTSIZE`, `LABEL_FONTSIZE`)."""
    for a in axes:
        a.tick_params(labelsize=TICK_FONTSIZE)
        a.xaxis.label.set_fontsize(LABEL_FONTSIZE)
        a.yaxis.label.set_fontsize(LABEL_FONTSIZE)


def unwrapped_phase(h: np.ndarray, keep: np.ndarray, reference=None) -> np.ndarray:
    """The phase of `h` in degrees, NaN where not `keep`; each contiguous stretch kept
    unwrapped on its own, then turned by the whole turns (360°) that bring it nearest
    `reference` (a model's phase), or, without one, that continue the stretch before it:
    a gap's noise does not add turns to what follows it."""
    out = np.full(h.shape, np.nan)
    idx = np.flatnonzero(keep)
    prev = None
    for seg in np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1) if idx.size else []:
        ph = np.degrees(np.unwrap(np.angle(h[seg])))
        if reference is not None:
            ph += 360.0 * np.round(np.mean(reference[seg] - ph) / 360.0)
        elif prev is not None:
            ph += 360.0 * np.round((prev - ph[0]) / 360.0)
        out[seg], prev = ph, ph[-1]
    return out


def bode_figure(f, H, coherence=None, averages: int | None = None, models=(),
                magnitude_label: str = "magnitude (dB)", title: str = "",
                xlabel: str = "frequency (Hz)", measured_label: str = "measured (H1)",
                min_coherence: float | None = None, command_psd=None):
    """A Bode plot, the one figure of every transfer function vtable draws (`tf --png`,
    the diagnosis and comparison reports): magnitude in dB on a log frequency axis,
    unwrapped phase, coherence beneath when given; with `averages`, the measured ±1σ
    band (`magnitude_band`); `models` (label, H, colour) drawn wide and translucent under
    the measured trace (black, thin, on top). With `min_coherence`, the measured trace and
    its band only where `supported` (γ² at least that, and the command's power
    `command_psd` within `COMMAND_POWER_MIN` of its peak), the rule in its legend and the
    threshold on the coherence axis; with `command_psd`, the models (estimates from the
    command too) only where it has power. Frequencies at or below 0 are left out (log
    axis)."""
    f, H = np.asarray(f), np.asarray(H)
    sel = f > 0
    f = f[sel]
    rows = 3 if coherence is not None else 2
    fig, ax = plt.subplots(rows, 1, sharex=True,
                           figsize=(WIDTH_IN, 8.0 if rows == 3 else 6.2),
                           gridspec_kw={"height_ratios": [3, 2, 1.2][:rows]})

    def db(h):
        return 20 * np.log10(np.maximum(np.abs(h), 1e-300))

    psd = None if command_psd is None else np.asarray(command_psd, float)[sel]
    powered = supported(np.ones(f.shape), psd, 0.0)  # a model's H1 too: not beyond the band
    reference = None  # the first model's phase: the measured one's 360° turns follow it
    for label, Hm, color in models:
        Hm = np.asarray(Hm)[sel]
        ph = unwrapped_phase(Hm, powered)
        reference = ph if reference is None else reference
        ax[0].semilogx(f, np.where(powered, db(Hm), np.nan), color=color, lw=MODEL_LW,
                       alpha=MODEL_ALPHA, label=label, zorder=MODEL_Z)
        ax[1].semilogx(f, ph, color=color, lw=MODEL_LW, alpha=MODEL_ALPHA, zorder=MODEL_Z)
    Hs = H[sel]
    coh = None if coherence is None else np.asarray(coherence)[sel]
    keep = np.ones(Hs.shape, bool)
    if coh is not None and min_coherence is not None:
        keep = supported(coh, psd, min_coherence)
        measured_label += f", shown where γ² ≥ {min_coherence:g}" + (
            " and the command has power" if command_psd is not None else "")
    mag = np.where(keep, np.abs(Hs), np.nan)
    if coh is not None and averages:
        eps = magnitude_band(Hs, coh, averages)
        ax[0].fill_between(f, db(mag * (1 - np.minimum(eps, 0.99))), db(mag * (1 + eps)),
                           color="0.75", lw=0, label="measured ±1σ", zorder=3)
    ax[0].semilogx(f, np.where(keep, db(Hs), np.nan), "k-", lw=MEASURED_LW,
                   label=measured_label, zorder=MEASURED_Z)
    ax[1].semilogx(f, unwrapped_phase(Hs, keep, reference), "k-", lw=MEASURED_LW,
                   zorder=MEASURED_Z)
    meas = db(Hs)[keep & np.isfinite(db(Hs))]
    if meas.size:  # a model far below the measurement does not crush its axis
        lo, hi = ax[0].get_ylim()
        ax[0].set_ylim(max(lo, float(meas.min()) - 40.0), hi)
    ax[0].set_ylabel(magnitude_label)
    ax[1].set_ylabel("phase (deg, unwrapped)")
    if coh is not None:
        ax[2].semilogx(f, coh, "k-", lw=MEASURED_LW)
        if min_coherence is not None:
            ax[2].axhline(min_coherence, color="tab:red", ls=":", lw=1.2,
                          label=f"γ² = {min_coherence:g}: measured drawn above")
            ax[2].legend(fontsize=LEGEND_FONTSIZE, loc="lower left")
        ax[2].set_ylabel("coherence γ²")
        ax[2].set_ylim(0, 1.05)
    ax[-1].set_xlabel(xlabel)
    for a in ax:
        a.grid(alpha=0.3, which="both")
    style_axes(*ax)
    if title:
        ax[0].set_title(title, fontsize=LABEL_FONTSIZE)
    if models or (coh is not None and averages):
        ax[0].legend(fontsize=LEGEND_FONTSIZE, loc="best")
    fig.tight_layout()
    return fig


def transfer_function_png(path: str | Path, f, H, coherence=None, title: str = "",
                          f_max: float | None = None, averages: int | None = None,
                          magnitude_label: str = "magnitude (dB)") -> Path:
    """`bode_figure` of H (a model's, or a run's with its coherence and averages) up to
    `f_max`, to a PNG file."""
    f, H = np.asarray(f), np.asarray(H)
    sel = np.ones(f.shape, bool) if f_max is None else f <= f_max
    coh = None if coherence is None else np.asarray(coherence)[sel]
    xlabel = "frequency (Hz)"
    if averages:
        xlabel += f"; {averages} averages, Δf {f[1] - f[0]:.3g} Hz" if f.size > 1 else ""
    return _save(bode_figure(f[sel], H[sel], coh, averages, magnitude_label=magnitude_label,
                             title=title, xlabel=xlabel), path)


def _save(fig, path: str | Path) -> Path:
    """Lay out, write as PNG (atomically, creating the folder) and close; a failed write is
    one line naming the path."""
    p = Path(path)
    try:
        fig.tight_layout()
        with atomic_path(p) as tmp:
            fig.savefig(tmp, dpi=110, format="png")
    finally:
        plt.close(fig)
    return p


def psv_spectra_png(path: str | Path, periods, psv: dict, title: str = "") -> Path:
    """Pseudo-velocity spectra of one record through several models (Figs 9.13-9.32)."""
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for name, v in psv.items():
        ax.loglog(periods, np.asarray(v) / 0.0254, lw=1.2, label=name)
    ax.set_xlabel("fixed-base period (s)")
    ax.set_ylabel("PSV (in/s)")
    ax.grid(alpha=0.3, which="both")
    ax.legend()
    ax.set_title(title)
    return _save(fig, path)


def coupled_sweep_png(path: str | Path, x, x_label: str, curves: dict, reference=None,
                      title: str = "") -> Path:
    """Coupled frequency ratio f_c/f_s and coupled damping ξ_c against a swept parameter
    (Figs 9.4-9.12). `curves`: label -> array (len(x), 2) of (f_c, ξ_c); `reference`: the
    fixed-base (f_s, ξ_s) at each x, for the ratio and the ξ_s line."""
    fig, ax = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
    x = np.asarray(x)
    ref = np.asarray(reference) if reference is not None else None
    for name, fc in curves.items():
        fc = np.asarray(fc)
        ax[0].plot(x, fc[:, 0] / ref[:, 0] if ref is not None else fc[:, 0], lw=1.2,
                   label=name)
        ax[1].plot(x, 100 * fc[:, 1], lw=1.2, label=name)
    if ref is not None:
        ax[1].plot(x, 100 * ref[:, 1], "k--", lw=1, label="fixed base")
    ax[0].set_ylabel("f_c / f_s" if ref is not None else "f_c (Hz)")
    ax[1].set_ylabel("coupled damping ξ_c (%)")
    ax[1].set_xlabel(x_label)
    for a in ax:
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
    fig.suptitle(title)
    return _save(fig, path)


def ductility_png(path: str | Path, y, period: float, title: str = "") -> Path:
    """Ductility demand and residual drift against period, fixed base and on the table
    (`vtable.studies.yielding.DuctilitySweep`), the specimen's own period marked."""
    fig, ax = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
    for values, label, style in ((y.ductility_fixed, "fixed base", "k--"),
                                 (y.ductility_table, "on the table", "C0-")):
        ax[0].plot(y.periods, values, style, lw=1.2, label=label)
    for values, label, style in ((y.residual_fixed, "fixed base", "k--"),
                                 (y.residual_table, "on the table", "C0-")):
        ax[1].plot(y.periods, np.abs(values) / 0.0254, style, lw=1.2, label=label)
    for a in ax:
        a.axvline(period, color="C3", lw=0.8, label="the specimen's period")
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
    ax[0].set_ylabel("ductility μ = max|u| / u_y")
    ax[1].set_ylabel("|residual drift| (in)")
    ax[1].set_xlabel("period (s)")
    fig.suptitle(title)
    return _save(fig, path)


def drive_png(path: str | Path, r, psa) -> Path:
    """`drive_figure` written as PNG."""
    return _save(drive_figure(r, psa), path)


def drive_figure(r, psa):
    """A drive (`vtable.drive.DriveResult`): the target, the predicted effective motion
    and the drive against time; the pseudo-acceleration spectra (`psa(x, f)`: of the
    displacement x at frequencies f, m/s²) of the target and of the effective motion
    under the drive and under the baselines compared with the target."""
    t, T = r.target.t, r.target.x
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 7))
    a1.plot(t, T / 0.0254, "k-", lw=1.2, label="target")
    a1.plot(t, r.drive.channels["x_eff"] / 0.0254, color="tab:blue", lw=0.9,
            label=f"predicted x_t + θh (NRMS {100 * r.drive.metrics['nrms']:.1f} %)")
    a1.plot(t, r.drive.drive / 0.0254, color="tab:orange", lw=0.7, alpha=0.8, label="drive")
    a1.set_xlabel("time (s)")
    a1.set_ylabel("displacement (in)")
    a1.legend(fontsize=8, loc="upper right")
    f = np.geomspace(0.5, 20.0, 80)
    curves = [("target", T, "k-"), ("x_t + θh under the drive", r.drive.channels["x_eff"],
                                    "b-")]
    curves += [(f"x_t + θh, {b.name}", b.channels["x_eff"], "--") for b in r.baselines
               if b.channels and "nrms" in b.metrics]
    for label, x, style in curves:
        a2.loglog(f, psa(x, f) / 9.80665, style, lw=1.1, label=label)
    a2.set_xlabel("frequency (Hz)")
    a2.set_ylabel("PSA, 5 % damped (g)")
    a2.grid(alpha=0.3, which="both")
    a2.legend(fontsize=8)
    fig.tight_layout()
    return fig
