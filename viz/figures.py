"""Matplotlib figures (PNG): transfer functions with coherence, response spectra and
coupled-mode sweeps."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from vtable.fileio import atomic_path

plt.switch_backend("Agg")  # figures are written to files: no window, whatever the default


def transfer_function_png(path: str | Path, f, H, coherence=None, title: str = "",
                          f_max: float | None = None) -> Path:
    """Amplitude, phase and coherence against frequency, as in the report's figures."""
    f, H = np.asarray(f), np.asarray(H)
    sel = f > 0 if f_max is None else (f > 0) & (f <= f_max)
    rows = 3 if coherence is not None else 2
    fig, ax = plt.subplots(rows, 1, sharex=True, figsize=(7, 2.2 * rows + 0.6))
    ax[0].plot(f[sel], np.abs(H[sel]), "k-", lw=1)
    ax[0].set_ylabel("amplitude")
    ax[1].plot(f[sel], np.degrees(np.angle(H[sel])), "k-", lw=1)
    ax[1].set_ylabel("phase (deg)")
    ax[1].set_yticks([-180, -90, 0, 90, 180])
    if coherence is not None:
        ax[2].plot(f[sel], np.asarray(coherence)[sel], "k-", lw=1)
        ax[2].set_ylabel("coherence")
        ax[2].set_ylim(0, 1.05)
    ax[-1].set_xlabel("frequency (Hz)")
    for a in ax:
        a.grid(alpha=0.3)
    fig.suptitle(title)
    return _save(fig, path)


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
