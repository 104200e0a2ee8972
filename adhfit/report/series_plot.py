"""fit.png and report.md of a global fit (issue 13): every curve with the shared fit and its residuals.

Draws from the stored predictions of a :class:`~adhfit.fitting.result.FitResult` with ``curves``
(``raw["series_plot"]``); never re-runs a fit.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .plots import _pyplot

__all__ = ["plot_series", "write_series_markdown", "series_markdown"]


def _kx(control: str) -> tuple[float, str]:
    return (1e6, "displacement (µm, measured)") if control == "displacement" else (1e-3, "pressure (kPa)")


def plot_series(result, *, path: str | Path | None = None):
    """Force of every curve with the shared fit, normalised residuals, and the contact radius (if fitted).

    Returns the matplotlib Figure.
    """
    plt = _pyplot()
    data = result.raw["series_plot"]
    radius = any("a" in d for d in data)
    n_rows = 3 if radius else 2
    fig, axes = plt.subplots(n_rows, 1, figsize=(7.0, 3.0 * n_rows), layout="constrained", sharex=True,
                             gridspec_kw={"height_ratios": [3, 1.4] + ([2] if radius else [])})
    kx, xlabel = _kx(data[0]["control"])
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, d in enumerate(data):
        c = colors[k % len(colors)]
        x = np.asarray(d["x"]) * kx
        axes[0].plot(x, np.asarray(d["force"]) * 1e3, ".", ms=2.5, color=c, label=f"{d['label']}")
        axes[0].plot(x, np.asarray(d["predicted"]) * 1e3, "-", lw=0.9, color=c)
        axes[1].plot(x, (np.asarray(d["force"]) - np.asarray(d["predicted"])) / d["sigma_force"], ".", ms=2.5, color=c)
        if "a" in d:
            rows = np.asarray(d["a_rows"])
            axes[2].plot(x[rows], np.asarray(d["a"]) * 1e6, ".", ms=2.5, color=c)
            axes[2].plot(x, np.asarray(d["a_predicted"]) * 1e6, "-", lw=0.9, color=c)
    p = result.parameters
    w, mu = p["work_of_adhesion"], p["mu_h"]
    axes[0].set_title(f"shared fit: W_ad = {w.value:.4g} J/m², μh = {mu.value:.4g} N/m; "
                      f"{result.slip['verdict']}", fontsize=9)
    axes[0].set_ylabel("force (mN)")
    axes[0].axhline(0.0, color="0.6", lw=0.6)
    axes[0].legend(fontsize=7)
    axes[1].axhline(0.0, color="0.6", lw=0.6)
    axes[1].set_ylabel("residual / σ_i")
    if radius:
        axes[2].set_ylabel("contact radius (µm)")
    axes[-1].set_xlabel(xlabel)
    if path is not None:
        fig.savefig(path, dpi=130)
        plt.close(fig)
    return fig


def _fmt(v, spec=".4g") -> str:
    return "—" if v is None else format(v, spec)


def series_markdown(result) -> str:
    """report.md of a global fit."""
    d = result.as_dict()
    lines = ["# adhfit global fit", "", f"Curves: {len(d['curves'])}; observables: {', '.join(d['observables'])}.",
             "", f"**Slip:** {d['slip']['verdict']}", "", "| parameter | value | 95 % | status | unit |",
             "|---|---|---|---|---|"]
    for name, e in d["parameters"].items():
        ci = "—" if e["ci95"] is None else f"[{_fmt(e['ci95'][0])}, {_fmt(e['ci95'][1])}]"
        lines.append(f"| {name} | {_fmt(e['value'])} | {ci} | {e['status']} | {e['unit']} |")
    lines += ["", "## Curves", "",
              "| file | rows | reduced χ² | W_ad alone | μh alone | pull on W_ad, μh (σ) | p | flags |",
              "|---|---|---|---|---|---|---|---|"]
    for c in d["curves"]:
        lo = c["leave_one_out"]
        s = lo["shift_in_stderr"]
        alone = c["alone"]
        lines.append(f"| {c['file']} | {c['n_points']} | {_fmt(c['redchi'], '.3g')} | "
                     f"{_fmt(alone['work_of_adhesion']['value'])} | {_fmt(alone['mu_h']['value'])} | "
                     f"{_fmt(s['work_of_adhesion'], '+.2g')}, {_fmt(s['mu_h'], '+.2g')} | {_fmt(lo['p_value'], '.2g')} | "
                     f"{', '.join(c['flags']) or '—'} |")
    lines += ["", "Pull: the shift of the shared value when the curve is left out, in joint standard errors; "
              "p: the chance of a pull this large if the curve agrees with the others (χ², 2 degrees of freedom).", ""]
    if d["warnings"]:
        lines += ["## Warnings", ""] + [f"- {w}" for w in d["warnings"]] + [""]
    return "\n".join(lines)


def write_series_markdown(result, path: str | Path) -> Path:
    path = Path(path)
    path.write_text(series_markdown(result), encoding="utf-8")
    return path
