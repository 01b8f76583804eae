"""When a candidate effect's held-out gain over the calibrated current model counts as a
missing effect rather than noise or a patch; the loop (`engine`) applies it.

Selection rule (`SELECTION`), on the held-out segments and on the squared scale where
sensor noise and a systematic error add (e² = mean over runs and channel groups of the
squared NRMS error; the noise alone costs f², the current model's systematic residual is
e² - f²; `statistics.held_out_gain`). A candidate is added only if its gain e²_current -
e²_candidate

1. exceeds `Z_NOISE` (5) standard errors of what the held-out noise produces between the two
   predictions: both were fitted on the training segments, so the held-out noise enters the
   gain only as 2 n·(ŷ_c - ŷ)/||y||², Gaussian with a variance the noise σ of every group
   gives (a likelihood-ratio test against the noise floor; white noise at the analysis rate);
2. removes at least `MIN_SHARE` (20 %) of the current model's systematic residual: the
   current model is itself calibrated, so this is what the effect explains that recalibrating
   the base cannot, and a small patch of a model-form difference is not a missing effect;
3. is at least 5 % of what the noise alone costs (f²; the reduced model's resolution,
   (0.5 %)², counts as noise where the sensors are quieter: `MODEL_RESOLUTION`): refitting
   the base and an effect to other noise moves a held-out error by less;

and (4) its fit is sound: no fitted effect parameter within 1 % of a bound (fitted scale),
correlated beyond 0.95 with a base parameter, or without influence on the data
(Gauss-Newton covariance at the solution). A candidate failing (4) is flagged in the
ranking and not added on that evidence; the next sound one may be. Base parameters at a
bound are flagged too but do not block: they say the model still lacks something.
"""

from __future__ import annotations

from vtable.diagnose.campaign import MODEL_RESOLUTION
from vtable.diagnose.statistics import Gain

Z_NOISE = 5.0  # the held-out gain must stand 5 standard errors above what noise produces ...
MIN_SHARE = 0.2  # ... remove 20 % of the current model's systematic residual (squared) ...
#: ... and be 5 % of what the noise alone costs (f²), the reduced model's own resolution
#: (`MODEL_RESOLUTION`, a floor below which it cannot tell physics from its approximations)
#: counting as noise when the sensors are quieter
NOISE_SHARE = 0.05
SELECTION = (f"an effect is added when, on the held-out last 40 % of every run and on the "
             f"scale where sensor noise and a systematic error add (the mean over runs and "
             f"channel groups of the squared NRMS error), its gain over the calibrated "
             f"current model (1) exceeds {Z_NOISE:g} standard errors of what the held-out "
             f"noise alone produces between the two predictions (a likelihood-ratio test "
             f"against the noise floor), (2) removes at least {MIN_SHARE:.0%} of the current "
             f"model's systematic residual (error^2 - floor^2) and (3) is at least "
             f"{NOISE_SHARE:.0%} of what the noise alone costs (floor^2; at least "
             f"({MODEL_RESOLUTION:.1%})^2, what the reduced model cannot resolve): refitting "
             "the base and an effect to other noise moves a held-out error by less; and "
             "its fit is sound: none of its own parameters within 1 % of a bound, correlated "
             "beyond 0.95 with a base parameter, or without influence on the data. The best "
             "such candidate (largest gain) is added. After each addition every effect added "
             "earlier is tested the same way against the model without it (refitted) and "
             "removed when it no longer passes")


def failing(g: Gain | None) -> list[str]:
    """The statistical criteria of `SELECTION` a held-out gain does not meet (empty: it
    passes)."""
    if g is None:
        return ["no valid model"]
    out = []
    if not g.z > Z_NOISE:
        out.append(f"its gain is {g.z:.1f} standard errors of the noise (needs {Z_NOISE:g})")
    if not g.gain >= MIN_SHARE * g.systematic:
        out.append(f"it removes {max(g.share, 0):.0%} of the systematic residual (needs "
                   f"{MIN_SHARE:.0%})")
    f2 = max(g.f2, MODEL_RESOLUTION**2)
    if not g.gain >= NOISE_SHARE * f2:
        out.append(f"its gain is {max(g.gain, 0) / f2:.0%} of what the noise alone costs "
                   f"(needs {NOISE_SHARE:.0%})" + ("" if g.f2 >= f2 else
                                                   f"; the noise taken at the reduced model's "
                                                   f"resolution, {MODEL_RESOLUTION:.1%}"))
    return out

