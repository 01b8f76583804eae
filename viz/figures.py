"""Matplotlib figures (PNG): transfer functions with coherence."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def transfer_function_png(path: str | Path, f, H, coherence=None, title: str = "",
                          f_max: float | None = None) -> Path:
    """Amplitude, phase and coherence against frequency, as in the report's figures."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

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
    fig.tight_layout()
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(p, dpi=110)
    plt.close(fig)
    return p
