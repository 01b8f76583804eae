"""The notes of a drive (`vtable.drive.compensate`) that explain its figures: the drive's
content above the table's rated band, and the cap near the specimen's fixed-base
frequencies."""

from __future__ import annotations

from typing import Any

#: a drive whose share of acceleration RMS above the table's band exceeds the target's by
#: more than this is said to ask for content the table is not rated for (a note)
BAND_MARGIN = 0.05


def above_band_note(shares: dict[str, float], response: dict[str, float], bw: float,
                    source: str, band_hz: float, default_band_hz: float,
                    motion: str) -> str | None:
    """The note on a drive holding more of its acceleration RMS above the table's rated
    band `bw` (Hz, from `source`) than the target (by `BAND_MARGIN`), None otherwise.

    `shares`: the share of the acceleration RMS above `bw` of the drive, the target and the
    predicted effective motion x_t + θh (`vtable.params.limits.share_above`); `response`:
    the model's |H| from the drive to the objective `motion` at the table's band and at the
    end of the correction band `band_hz`. The drive's content above the band is the
    target's own there over the table's response: the note says both, so that the cause
    can be read."""
    if not shares["drive"] > shares["target"] + BAND_MARGIN:
        return None
    default = f", by default {default_band_hz:g} Hz" if band_hz == default_band_hz else ""
    return (f"{100 * shares['drive']:.0f} % of the drive's acceleration RMS lies above the "
            f"table's {bw:g} Hz band ({source}), against {100 * shares['target']:.0f} % of "
            f"the target's and {100 * shares['motion']:.0f} % of the predicted effective "
            f"motion's: the table's response from the drive to {motion} falls to "
            f"{response['table_band']:.2f} at {bw:g} Hz and {response['correction_band']:.2f}"
            f" at {band_hz:g} Hz, and the drive makes that up so that the motion holds the "
            f"target's content; the correction runs to {band_hz:g} Hz (--band{default}) so "
            f"that the spectrum is corrected up to the table's {bw:g} Hz, and asks the table "
            f"for content where its performance is not rated; --band {bw:g} keeps the drive "
            "within the rated band (the spectrum near it is then not corrected)")


def cap_note(amp: dict[str, Any], cap: float, uncapped: float, capped: float) -> str | None:
    """The note on the cap, when it acted: the amplification near the fixed base before it
    and after it (`capped_near_fixed_base`'s figures), and the model's NRMS before and
    after (fractions); None when the cap did not act."""
    if not amp["capped"]:
        return None
    after = (f"held to the cap {cap:g} there ({amp['near_fixed_base']:.2f})" if amp["held"]
             else f"capped at {cap:g} there, it still reaches {amp['near_fixed_base']:.1f} "
                  "(the smoothed spectrum moves as the drive is scaled)")
    return (f"the drive's amplification of the target near the specimen's fixed-base "
            f"frequency reached {amp['near_fixed_base_uncapped']:.1f}; {after} (the model's "
            f"NRMS {100 * uncapped:.2f} % -> {100 * capped:.2f} %; raise --cap to follow the "
            "target closer)")
