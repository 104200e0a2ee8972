"""MCMC plots: the corner plot of a slip condition's posterior (least-squares point marked) and the data
with the posterior-predictive band.  Draw from a stored :class:`~adhfit.fitting.result.FitResult` of an MCMC fit;
never re-run anything."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .plots import pyplot, save
from .view import display

__all__ = ["plot_corner", "plot_predictive"]


def _label(name: str) -> tuple[float, str]:
    """SI -> display factor and axis label of a sampled parameter (symbols and units of the view layer)."""
    sym, _, k, unit = display(name)
    return k, f"{sym} ({unit})" if unit else sym


def plot_corner(result, slip: str | None = None, *, path: str | Path | None = None):
    """Corner plot (``corner`` package) of one slip condition's posterior, least-squares optimum marked.

    Parameters
    ----------
    result : FitResult
        Of an MCMC fit (with ``sampling``).
    slip : str, optional
        Default: the reported slip condition.
    path : path, optional
        Save the figure there.

    Returns
    -------
    matplotlib.figure.Figure

    Notes
    -----
    A series shows its shared W_ad and μh only (its per-curve offsets are in the report's Curves table;
    a panel per offset pair would grow with the square of the number of curves).
    """
    pyplot()
    import corner  # noqa: PLC0415
    slip = slip or result.slip["parameters_from"]
    every = list(result.mcmc["slips"][slip]["parameters"])
    names = [n for n in every if not result.curves or n in ("work_of_adhesion", "mu_h")]
    k = np.array([_label(n)[0] for n in names])
    samples = np.asarray(result.samples[slip])[:, [every.index(n) for n in names]] * k
    lsq = (result.mcmc.get("lsq_estimates") or {}).get(slip) or {}
    truths = [None if lsq.get(n) is None else lsq[n] * f for n, f in zip(names, k)]
    fig = corner.corner(samples, labels=[_label(n)[1] for n in names], truths=truths,
                        truth_color="#d62728", quantiles=[0.025, 0.5, 0.975], show_titles=True,
                        title_fmt=".4g", title_kwargs={"fontsize": 8}, label_kwargs={"fontsize": 9})
    fig.suptitle(f"posterior, {slip} ({len(samples)} samples; red: least squares)"
                 + ("" if result.mcmc["slips"][slip]["diagnostics"]["converged"]
                    else " — NOT CONVERGED"), fontsize=9, y=0.995)
    fig.subplots_adjust(top=0.9)  # room for the suptitle above the first panel's own title
    if path is not None:
        save(fig, path, dpi=110)
    return fig


def plot_predictive(result, *, ax=None, path: str | Path | None = None):
    """Data with the posterior median model and its 95 % bands (model curve; new observations).

    Parameters
    ----------
    result : FitResult
        Of an MCMC fit (with ``sampling``).
    ax : matplotlib Axes, optional
    path : path, optional

    Returns
    -------
    matplotlib.axes.Axes
    """
    plt = pyplot()
    if ax is None:
        _, ax = plt.subplots(figsize=(7.0, 4.8), layout="constrained")
    c, seg, band = result.curve, result.segments, result.predictive
    kx, xlabel = (1e6, "displacement (µm, measured)") if c.control == "displacement" else (1e-3, "pressure (kPa)")
    n = len(c.x)
    idx = np.arange(n)
    end = n if seg["i_jump"] is None else seg["i_jump"]
    parts = (("loading", idx <= seg["i_turn"], "#1f77b4"), ("unloading", (idx > seg["i_turn"]) & (idx < end), "#d62728"),
             ("after pull-off", idx >= end, "0.5"))
    for label, m, color in parts:
        if not m.any():
            continue
        ax.plot(c.x[m] * kx, c.force[m] * 1e3, ".", ms=3, color=color, label=f"data: {label}")
        if label == "after pull-off":
            continue
        o = np.argsort(c.x[m])
        x = c.x[m][o] * kx
        ax.fill_between(x, band["lo_obs"][m][o] * 1e3, band["hi_obs"][m][o] * 1e3, color=color, alpha=0.15, lw=0,
                        label=f"95 % posterior predictive ({label})")
        ax.fill_between(x, band["lo"][m][o] * 1e3, band["hi"][m][o] * 1e3, color=color, alpha=0.4, lw=0)
        ax.plot(x, band["median"][m][o] * 1e3, "-", color="k", lw=0.9)
    ax.plot([], [], "-", color="k", lw=0.9, label=f"posterior median model ({band['slip']}); dark: 95 % of the curve")
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("force (mN, compressive positive)")
    conv = "" if result.converged else " — MCMC NOT CONVERGED"
    ax.set_title(f"{result.slip['verdict']}; {band['draws']} posterior draws{conv}", fontsize=10)
    ax.legend(fontsize=7)
    if path is not None:
        save(ax.figure, path)
    return ax
