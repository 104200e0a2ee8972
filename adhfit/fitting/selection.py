"""Slip selection: compare the no-slip and frictionless fits by AIC and BIC (DESIGN.md B4).

A single fit's χ² cannot tell the slip condition (at 0.5 % noise the wrong model's reduced χ² can
still look acceptable); the comparison of the two fits can.  Both fits have the same data and the
same number of parameters k, so ΔAIC = ΔBIC = Δ(-2 ln L):

* σ estimated:  -2 ln L = n ln(RSS/n) (+ const), AIC = n ln(RSS/n) + 2k, BIC = n ln(RSS/n) + k ln n;
* σ given:      -2 ln L = χ² (+ const),          AIC = χ² + 2k,          BIC = χ² + k ln n.

Evidence scale on ΔBIC (Kass & Raftery 1995, on 2 ln B): > 10 **decisive** — the better condition is
selected; 2 – 10 **positive** — it is favoured with caution and *not* selected; < 2 **none**.
Only a decisive difference selects: a wrong selection then needs the wrong model to win by more than
10, which (for models whose predictions differ by s in units of σ², Δ ~ N(s, 4s)) happens with a
probability below 0.1 % for any s.  The verdict is one of ``"no-slip favoured"``,
``"frictionless favoured"``, ``"the data cannot tell them apart"``.
"""
from __future__ import annotations

import math

__all__ = ["information_criteria", "compare", "DECISIVE", "POSITIVE", "VERDICTS"]

DECISIVE = 10.0
POSITIVE = 2.0
VERDICTS = ("no-slip favoured", "frictionless favoured", "the data cannot tell them apart")


def information_criteria(chisqr: float, ndata: int, nvarys: int, *, sigma_given: bool) -> tuple[float, float]:
    """(AIC, BIC) of a least-squares fit (see the module docstring for the definitions)."""
    if sigma_given:
        m2lnl = chisqr
    else:
        m2lnl = ndata * math.log(max(chisqr, 1e-300) / ndata)
    return m2lnl + 2 * nvarys, m2lnl + nvarys * math.log(ndata)


def compare(bic: dict[str, float], aic: dict[str, float]) -> dict:
    """Verdict on the slip condition from the two fits' BIC (and AIC, reported alongside).

    Parameters
    ----------
    bic, aic : dict slip -> float
        Both conditions' criteria (one entry only when the user imposed the condition).

    Returns
    -------
    dict
        ``selected`` (None unless decisive), ``verdict``, ``evidence``, ``favoured``, ``delta_aic``,
        ``delta_bic`` (the other condition's minus the favoured one's, >= 0), ``thresholds``,
        ``parameters_from`` (the condition whose estimates are reported).
    """
    thresholds = {"decisive": DECISIVE, "positive": POSITIVE, "criterion": "delta_bic"}
    if len(bic) == 1:
        (only,) = bic
        return {"selected": only, "verdict": f"{only} (set by the user; not compared)", "evidence": "imposed",
                "favoured": only, "delta_aic": None, "delta_bic": None, "thresholds": thresholds,
                "parameters_from": only}
    ranked = sorted(bic, key=lambda k: bic[k])
    best, other = ranked[0], ranked[1]
    d_bic = bic[other] - bic[best]
    d_aic = aic[other] - aic[best]
    if not math.isfinite(d_bic):
        evidence = "none"
    elif d_bic > DECISIVE:
        evidence = "decisive"
    elif d_bic >= POSITIVE:
        evidence = "positive"
    else:
        evidence = "none"
    selected = best if evidence == "decisive" else None
    verdict = f"{best} favoured" if selected else VERDICTS[2]
    explanation = {
        "decisive": f"ΔBIC = {d_bic:.1f} > {DECISIVE:g}: {best} is selected.",
        "positive": f"ΔBIC = {d_bic:.1f} in [{POSITIVE:g}, {DECISIVE:g}]: {best} is favoured with caution, "
                    f"not selected.",
        "none": f"ΔBIC = {d_bic:.1f} < {POSITIVE:g}: no preference."}[evidence]
    return {"selected": selected, "verdict": verdict, "evidence": evidence, "favoured": best,
            "delta_aic": d_aic, "delta_bic": d_bic, "explanation": explanation, "thresholds": thresholds,
            "parameters_from": best}
