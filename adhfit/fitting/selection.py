"""Slip selection: compare the no-slip and frictionless fits by AIC and BIC (docs/numerics.md B4).

A single fit's χ² cannot tell the slip condition (at 0.5 % noise the wrong model's reduced χ² can
still look acceptable); the comparison of the two fits can.  Both fits have the same data and the
same number of parameters k, so ΔAIC = ΔBIC = Δ(-2 ln L):

* σ estimated:  -2 ln L = n ln(RSS/n) (+ const), AIC = n ln(RSS/n) + 2k, BIC = n ln(RSS/n) + k ln n;
* σ given:      -2 ln L = χ² (+ const),          AIC = χ² + 2k,          BIC = χ² + k ln n.

Evidence scale on ΔBIC (Kass & Raftery 1995, on 2 ln B), the one the report prints
(:data:`SCALE`): < 2 **cannot tell**, 2 – 6 **positive**, 6 – 10 **strong**, > 10 **very strong**.
Only very strong evidence selects: a wrong selection then needs the wrong model to win by more than
10, which (for models whose predictions differ by s in units of σ², Δ ~ N(s, 4s)) happens with a
probability below 0.1 % for any s.  Below that the better condition is named with its evidence word
and ``selected`` is null.  The verdict always carries the scale's word, e.g. ``"no-slip: very
strong evidence (ΔBIC = 1071)"``; when the data cannot tell it is ``"the data cannot tell them apart"``.
"""
from __future__ import annotations

import math

__all__ = ["information_criteria", "compare", "evidence_word", "DECISIVE", "POSITIVE", "STRONG", "VERDICTS", "SCALE"]

DECISIVE = 10.0
POSITIVE = 2.0
STRONG = 6.0
VERDICTS = ("no-slip favoured", "frictionless favoured", "the data cannot tell them apart")
#: (lower ΔBIC, word) of the evidence scale, weakest first
SCALE = ((0.0, "cannot tell"), (POSITIVE, "positive"), (STRONG, "strong"), (DECISIVE, "very strong"))


def evidence_word(delta_bic: float) -> str:
    """The scale's word for a ΔBIC (>= 0; not finite: "cannot tell")."""
    if not math.isfinite(delta_bic) or delta_bic < POSITIVE:
        return "cannot tell"
    if delta_bic < STRONG:
        return "positive"
    return "strong" if delta_bic <= DECISIVE else "very strong"


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
    thresholds = {"decisive": DECISIVE, "strong": STRONG, "positive": POSITIVE, "criterion": "delta_bic"}
    if len(bic) == 1:
        (only,) = bic
        return {"selected": only, "verdict": f"{only} (set by the user; not compared)", "evidence": "imposed",
                "favoured": only, "delta_aic": None, "delta_bic": None, "thresholds": thresholds,
                "parameters_from": only}
    ranked = sorted(bic, key=lambda k: bic[k])
    best, other = ranked[0], ranked[1]
    d_bic = bic[other] - bic[best]
    d_aic = aic[other] - aic[best]
    word = evidence_word(d_bic)
    selected = best if word == "very strong" else None
    if word == "cannot tell":
        verdict = VERDICTS[2]
        explanation = f"ΔBIC = {d_bic:.1f} < {POSITIVE:g}: the data cannot tell the slip conditions apart."
    elif selected:
        verdict = f"{best}: very strong evidence (ΔBIC = {d_bic:.3g})"
        explanation = f"ΔBIC = {d_bic:.1f} > {DECISIVE:g}: very strong evidence for {best}, which is selected."
    else:
        verdict = f"{best}: {word} evidence, not selected (ΔBIC = {d_bic:.2g})"
        explanation = (f"ΔBIC = {d_bic:.1f}: {word} evidence for {best}; only ΔBIC > {DECISIVE:g} (very strong) "
                       f"selects a slip condition.")
    return {"selected": selected, "verdict": verdict, "evidence": word, "favoured": best,
            "delta_aic": d_aic, "delta_bic": d_bic, "explanation": explanation, "thresholds": thresholds,
            "scale": [{"delta_bic_from": lo, "word": w} for lo, w in SCALE],
            "parameters_from": best}
