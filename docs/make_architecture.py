"""Draw docs/img/architecture.svg, the packages in their layers (docs/architecture.md):

    python docs/make_architecture.py

The layers and the arrows allowed to point up are the ones `tests/unit/test_imports.py`
holds (`LAYERS`, `UPWARD`); the package graph it measures decides which upward arrows are
drawn, so the picture is the code's. Every other import between packages points down."""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.patches import FancyArrowPatch, FancyBboxPatch

HERE = Path(__file__).resolve().parent
OUT = HERE / "img" / "architecture.svg"
BOX_W, BOX_H, GAP = 1.55, 0.62, 0.18  # a package's box and the space between two (inches)
PER_ROW = 3  # boxes in a row (a wider layer takes several)


def positions(layers: Sequence[Sequence[str]]) -> dict[str, tuple[float, float]]:
    """Each package's box centre: the bottom layer lowest, a layer's boxes in rows of at
    most `PER_ROW`, centred."""
    out, y = {}, 0.0
    for layer in layers:
        for start in range(0, len(layer), PER_ROW):
            row = layer[start:start + PER_ROW]
            width = len(row) * BOX_W + (len(row) - 1) * GAP
            for k, name in enumerate(row):
                out[name] = (-width / 2 + BOX_W / 2 + k * (BOX_W + GAP), y)
            y += BOX_H + 0.22
    return out


def layer_table(page: Path = HERE / "architecture.md") -> list[tuple[tuple[str, ...], str]]:
    """The page's table of layers, bottom up: (the packages, the one job) of each row."""
    rows = []
    for line in page.read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 3 and cells[0].isdigit():
            if int(cells[0]) != len(rows):
                raise ValueError(f"{page}: layer {cells[0]} is row {len(rows)}")
            rows.append((tuple(c.strip().strip("`") for c in cells[1].split(",")), cells[2]))
    return rows


def jobs(page: Path = HERE / "architecture.md") -> dict[int, str]:
    """Each layer's one job, as the page's table says it (its first clause)."""
    out = {}
    for row, (_, job) in enumerate(layer_table(page)):
        job = job.replace("`", "")
        for stop in (": ", "; ", " ("):
            job = job.split(stop)[0]
        out[row] = job
    return out


def draw(layers: Sequence[Sequence[str]], upward: Sequence[tuple[str, str]],
         out: Path = OUT, job: dict[int, str] | None = None) -> list[tuple[str, str]]:
    """Draw the layers (each with its `job`) and the `upward` arrows (package, package it
    imports) to `out`; returns the arrows drawn."""
    job = job or {}
    plt.rcParams["svg.fonttype"] = "none"  # the names stay text (searchable, testable)
    plt.rcParams["svg.hashsalt"] = "vtable"
    pos = positions(layers)
    widest = min(PER_ROW, max(len(layer) for layer in layers)) * (BOX_W + GAP)
    top = max(y for _, y in pos.values())
    fig, ax = plt.subplots(figsize=(widest + 6.5, top + 1.6))
    for row, layer in enumerate(layers):
        y = (pos[layer[0]][1] + pos[layer[-1]][1]) / 2
        ax.text(-widest / 2 - 0.55, y, str(row), ha="right", va="center", fontsize=9,
                color="#777777")
        for name in layer:
            x, y = pos[name]
            ax.add_patch(FancyBboxPatch((x - BOX_W / 2, y - BOX_H / 2), BOX_W, BOX_H,
                                        boxstyle="round,pad=0.02,rounding_size=0.08",
                                        facecolor="#e8eef7", edgecolor="#3b5b8c", lw=1.0))
            ax.text(x, y, name, ha="center", va="center", fontsize=10, family="monospace")
        y = (pos[layer[0]][1] + pos[layer[-1]][1]) / 2
        ax.text(widest / 2 + 0.25, y, job.get(row, ""), ha="left", va="center", fontsize=9,
                color="#333333")
    drawn = []
    for a, b in upward:
        (xa, ya), (xb, yb) = pos[a], pos[b]
        ax.add_patch(FancyArrowPatch((xa - BOX_W / 2, ya), (xb - BOX_W / 2, yb),
                                     connectionstyle="arc3,rad=0.35", arrowstyle="-|>",
                                     mutation_scale=12, color="#b03a2e", lw=1.2,
                                     linestyle="--"))
        drawn.append((a, b))
    ax.text(-widest / 2 - 0.55, top + 0.75,
            "A package imports only its own layer or those below it.\nDashed: the plotting "
            "hook (a result's .report() / .rerun() load their renderer when called).",
            fontsize=9, va="bottom")
    ax.set_xlim(-widest / 2 - 1.0, widest / 2 + 5.5)
    ax.set_ylim(-0.6, top + 1.1)
    ax.set_axis_off()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, format="svg", bbox_inches="tight", metadata={"Date": None})
    plt.close(fig)
    return drawn


def main() -> None:
    sys.path.insert(0, str(HERE.parent / "tests" / "unit"))
    import test_imports as rules

    arrows = rules.package_arrows()
    upward = sorted(k for k in rules.UPWARD if k in arrows)
    draw([list(layer) for layer in rules.LAYERS], upward, job=jobs())
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
