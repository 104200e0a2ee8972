"""report.md of a global (series) fit: the shared values, the slip verdict, every curve, the warnings.

Rendered from the report.json dictionary (the same words as report.html, :mod:`.series_text`).
"""
from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .series_text import (
    CURVE_HEADER,
    SLIP_HEADER,
    curve_legend,
    curve_rows,
    slip_rows,
    width_comparison,
)
from .text import display, estimate_text, interval_text, seed_text

__all__ = ["series_markdown", "write_series_markdown"]

_METHOD = {"lsq": "least squares, one joint fit", "mcmc": "Bayesian (MCMC) on the joint posterior"}


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    cell = lambda x: str(x).replace("|", "\\|")  # noqa: E731
    return (["| " + " | ".join(map(cell, header)) + " |", "|" + "---|" * len(header)]
            + ["| " + " | ".join(map(cell, r)) + " |" for r in rows])


def _shared(d: Mapping[str, Any]) -> list[str]:
    rows = []
    for name, est in (d.get("parameters") or {}).items():
        sym, _, k, unit = display(name, est.get("unit"))
        value = est.get("value")
        se = est.get("stderr")
        rows.append([sym, "n/a" if value is None else f"{value * k:.4g}", interval_text(name, est, unit=False),
                     "n/a" if se is None else f"{se * k:.2g}", str(est.get("status")).replace("_", " "), unit])
    return _table(["quantity", "value", "95 % interval", "std. error", "status", "unit"], rows)


def _mcmc(d: Mapping[str, Any]) -> list[str]:
    m = d.get("mcmc")
    if not isinstance(m, Mapping):
        return []
    out = ["## MCMC", "", f"{'Converged' if m.get('converged') else '**NOT CONVERGED** — do not trust the intervals'}; "
           f"seed {m.get('seed')}; {m.get('noise_model')}.", ""]
    rows = []
    for s, v in (m.get("slips") or {}).items():
        g = v.get("diagnostics") or {}
        rhat = max((x for x in (g.get("rhat") or {}).values() if isinstance(x, (int, float))), default=None)
        tau = max((x for x in (g.get("tau") or {}).values() if isinstance(x, (int, float))), default=None)
        ess = min((x for x in (g.get("ess_bulk") or {}).values() if isinstance(x, (int, float))), default=None)
        rows.append([s, "yes" if g.get("converged") else "**no**", f"{rhat:.4f}" if rhat else "n/a",
                     f"{tau:.3g}" if tau else "n/a", f"{ess:.0f}" if ess else "n/a",
                     f"{v.get('mcmc_seconds', 0):.0f} s"])
    return out + _table(["slip", "converged", "largest R-hat", "largest τ (steps)", "least bulk ESS", "time"], rows) + [""]


def series_markdown(d: Mapping[str, Any]) -> str:
    """report.md of a global fit, from its report.json dictionary."""
    if not isinstance(d, Mapping):
        d = d.as_dict()
    slip = d.get("slip") or {}
    curves = d.get("curves") or []
    lines = ["# adhfit global fit", "",
             f"{len(curves)} curves of one membrane; {_METHOD.get(d.get('method'), d.get('method'))}; "
             f"{seed_text(d)}; fitted to: {', '.join(d.get('observables') or [])}.", "",
             f"**Slip:** {slip.get('verdict')}", ""]
    lines += [f"**{display(k)[0]}** = {estimate_text(k, v)} ({str(v.get('status')).replace('_', ' ')})  "
              for k, v in (d.get("parameters") or {}).items()]
    lines += ["", "## Shared values", ""] + _shared(d) + [""]
    width = width_comparison(d)
    if width:
        lines += [width, ""]
    lines += ["## Slip condition", "", str(slip.get("explanation") or ""), ""] + _table(SLIP_HEADER[:len(slip_rows(d)[0])] if slip_rows(d) else SLIP_HEADER, slip_rows(d))
    lines += ["", "## Curves", ""] + _table(CURVE_HEADER, curve_rows(d)) + [""]
    lines += [f"- {x}" for x in curve_legend()] + [""]
    lines += _mcmc(d)
    warnings = d.get("warnings") or []
    lines += ["## Warnings", ""] + ([f"- {w}" for w in warnings] if warnings else ["None."]) + [""]
    prov = d.get("provenance") or {}
    lines += ["## Provenance", "", f"adhfit {prov.get('adhfit_version')}; {d.get('wall_time_s', 0):.1f} s.", ""]
    lines += _table(["#", "input file", "SHA-256", "scene file"],
                    [[str(k + 1), f"`{f}`", f"`{s}`", f"`{sc}`"] for k, (f, s, sc) in enumerate(
                        zip(prov.get("input") or [], prov.get("input_sha256") or [], prov.get("scene_file") or []))])
    return "\n".join(lines) + "\n"


def write_series_markdown(result, path: str | Path) -> Path:
    """Write :func:`series_markdown` of ``result`` (a FitResult with ``curves`` or its dictionary)."""
    path = Path(path)
    path.write_text(series_markdown(result if isinstance(result, Mapping) else result.as_dict()), encoding="utf-8")
    return path
