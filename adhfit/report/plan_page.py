"""The page of a test plan (``adhfit plan``: DIR/report.html): maps a person reads at a glance.

Two maps over the two varied settings: the expected 95 % width of W_ad (as a percentage of W_ad) and
the probability that the fit decides the slip (the lesser of the true conditions planned for); cells
outside the model's domain are hatched, the recommended protocol is a star, and the contours mark the
requested precision and P = 0.9.  One varied setting gives two curves; none, a table only.
"""
from __future__ import annotations

import base64
import html
import io
import math

import numpy as np

from .files import write_text

__all__ = ["plan_figure", "plan_html", "write_plan_page"]

_LABELS = {"pressure": ("pressure", "kPa", 1e-3), "gap": ("gap", "mm", 1e3), "a_max": ("a_max = a/b", "", 1.0),
           "displacement_max": ("largest displacement", "mm", 1e3), "pressure_max": ("largest pressure", "kPa", 1e-3),
           "rows": ("rows", "", 1.0), "noise": ("noise", "% of peak force", 100.0)}


def _label(name: str) -> str:
    text, unit, _ = _LABELS.get(name, (name, "", 1.0))
    return f"{text} [{unit}]" if unit else text


def _scale(name: str) -> float:
    return _LABELS.get(name, (name, "", 1.0))[2]


def _fields(plan: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    w = plan["inputs"]["work_of_adhesion"]
    width, p, inside = [], [], []
    for e in plan["protocols"]:
        v = e["ci95_width"]["work_of_adhesion"]
        width.append(100 * v / w if e["in_domain"] and v is not None and math.isfinite(v) else np.nan)
        ps = list(e["p_slip_decided"].values())
        p.append(min(ps) if e["in_domain"] and None not in ps else np.nan)
        inside.append(bool(e["in_domain"]))
    return np.array(width), np.array(p), np.array(inside)


def plan_figure(plan: dict):
    """The maps (or curves) of a plan dict (plan.json); ``None`` without a varied setting."""
    names = list(plan["axes"])
    if not names:
        return None
    import matplotlib  # noqa: PLC0415
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415
    width, p, inside = _fields(plan)
    target = 100 * plan["inputs"]["target_precision"]
    rec = plan["recommended"]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.4), constrained_layout=True)
    if len(names) == 1:
        x = np.asarray(plan["axes"][names[0]]) * _scale(names[0])
        for ax, y, title, line in ((axes[0], width, "expected 95 % width of W_ad [% of W_ad]", target),
                                   (axes[1], p, "P(slip decided)", 0.9)):
            ax.plot(x, y, "o-", color="C0")
            ax.axhline(line, color="C3", ls="--", lw=1, label="required")
            if rec is not None:
                ax.plot(x[rec], y[rec], "*", ms=16, color="C1", label="recommended")
            for xi in x[~inside]:
                ax.axvspan(xi - 0.5 * np.ptp(x) / max(len(x) - 1, 1), xi + 0.5 * np.ptp(x) / max(len(x) - 1, 1),
                           color="0.85", zorder=0)
            ax.set_xlabel(_label(names[0]))
            ax.set_title(title)
            ax.legend(loc="best", fontsize=8)
        axes[1].set_ylim(-0.02, 1.02)
        return fig
    ya, xa = (np.asarray(plan["axes"][n]) * _scale(n) for n in names)
    shape = (len(ya), len(xa))
    panels = ((axes[0], width.reshape(shape), "expected 95 % width of W_ad [% of W_ad]", "viridis_r", target),
              (axes[1], p.reshape(shape), "P(slip decided), lesser of the true slips", "RdYlGn", 0.9))
    for ax, z, title, cmap, level in panels:
        kw = {"vmin": 0.0, "vmax": 1.0} if "P(" in title else {"norm": _log_norm(z)}
        mesh = ax.pcolormesh(xa, ya, np.ma.masked_invalid(z), shading="nearest", cmap=cmap, **kw)
        fig.colorbar(mesh, ax=ax)
        _hatch(ax, xa, ya, ~inside.reshape(shape))
        if np.isfinite(z).sum() >= 4 and np.nanmin(z) < level < np.nanmax(z):
            cs = ax.contour(xa, ya, np.ma.masked_invalid(z), levels=[level], colors="k", linewidths=1.2)
            ax.clabel(cs, fmt=(lambda v: f"{v:.3g} %") if "width" in title else (lambda v: f"P = {v:.1f}"), fontsize=8)
        if rec is not None:
            i, j = divmod(rec, len(xa))
            ax.plot(xa[j], ya[i], "*", ms=18, color="white", mec="k", mew=1.2, label="recommended")
            ax.legend(loc="upper right", bbox_to_anchor=(1.0, -0.13), fontsize=8, frameon=False)
        ax.set_xlabel(_label(names[1]))
        ax.set_ylabel(_label(names[0]))
        ax.set_title(title, fontsize=10)
    return fig


def _edges(v: np.ndarray) -> np.ndarray:
    """Cell edges around grid values (the midpoints; half a step beyond the ends)."""
    if v.size == 1:
        return np.array([v[0] - 0.5, v[0] + 0.5])
    mid = 0.5 * (v[1:] + v[:-1])
    return np.concatenate([[v[0] - (mid[0] - v[0])], mid, [v[-1] + (v[-1] - mid[-1])]])


def _hatch(ax, xa, ya, out) -> None:
    """Hatch the cells outside the model's domain."""
    from matplotlib.patches import Rectangle  # noqa: PLC0415
    ex, ey = _edges(xa), _edges(ya)
    for i, j in zip(*np.nonzero(out)):
        ax.add_patch(Rectangle((ex[j], ey[i]), ex[j + 1] - ex[j], ey[i + 1] - ey[i], facecolor="0.9",
                               edgecolor="0.55", hatch="///", lw=0, zorder=1))


def _log_norm(z):
    from matplotlib.colors import LogNorm  # noqa: PLC0415
    finite = z[np.isfinite(z) & (z > 0)]
    if finite.size == 0:
        return None
    lo, hi = float(finite.min()), float(finite.max())
    if hi < 10 * lo:  # a linear scale reads better over less than a decade
        from matplotlib.colors import Normalize  # noqa: PLC0415
        return Normalize(vmin=lo, vmax=max(hi, lo * 1.01))
    return LogNorm(vmin=lo, vmax=hi)


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    import matplotlib.pyplot as plt  # noqa: PLC0415
    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _fmt(v) -> str:
    if v is None:
        return "–"
    if isinstance(v, float):
        return "∞" if math.isinf(v) else f"{v:.4g}"
    return html.escape(str(v))


def _table(plan: dict) -> str:
    w, mu = plan["inputs"]["work_of_adhesion"], plan["inputs"]["mu_h"]
    slips = plan["inputs"]["slips"]
    head = ["#", "settings (SI)", "W_ad width [%]", "μh width [%]"] + [f"P(decided | {s})" for s in slips] + \
        [f"P(wrong | {s})" for s in slips] + ["in domain", "membrane"]
    rows = []
    for i, e in enumerate(plan["protocols"]):
        s = e["settings"]
        settings = ", ".join(f"{k} = {_fmt(v)}" for k, v in s.items() if k != "control")
        ww, wm = e["ci95_width"]["work_of_adhesion"], e["ci95_width"]["mu_h"]
        cells = [str(i), settings, _fmt(100 * ww / w if ww is not None else None),
                 _fmt(100 * wm / mu if wm is not None else None)]
        cells += [_fmt(e["p_slip_decided"][s]) for s in slips] + [_fmt(e["p_wrong_slip"][s]) for s in slips]
        cells += ["yes" if e["in_domain"] else f"no: {_fmt(e.get('why_not', ''))}", _fmt(e["membrane"])]
        style = ' class="rec"' if i == plan["recommended"] else ""
        rows.append(f"<tr{style}>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
    return "<table><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in head) + "</tr>" + "".join(rows) + "</table>"


def _series(plan: dict) -> str:
    s = plan.get("series")
    if not s:
        return ""
    return (f"<h2>Test series (--global {s['k']})</h2><p>{html.escape(s['why'])}</p>"
            f"<pre>{html.escape(_series_text(s))}</pre>")


def _series_text(s: dict) -> str:
    lines = [f"{k}: {v}" for k, v in s.items() if k not in ("why",)]
    return "\n".join(lines)


def plan_html(plan: dict) -> str:
    """The report page of a plan dict (plan.json), maps embedded."""
    inp = plan["inputs"]
    fig = plan_figure(plan)
    img = f'<img alt="maps" src="data:image/png;base64,{_png(fig)}">' if fig is not None else ""
    rec = plan["recommended"]
    head = (f"<p><b>Planned for</b> W_ad = {inp['work_of_adhesion']:.4g} J/m², μh = {inp['mu_h']:.4g} N/m, noise "
            f"{100 * inp['noise']:.3g} % of the peak force, {inp['rows']} rows, true slip: {', '.join(inp['slips'])}; "
            f"required: P(slip decided) ≥ {inp['p_decided_required']:g} and a W_ad 95 % width ≤ "
            f"{100 * inp['target_precision']:.3g} % of W_ad.</p>")
    verdict = (f"<p class='ok'><b>Recommended: protocol {rec}</b> — {html.escape(plan['why'])}. Its scene: scene.toml.</p>"
               if rec is not None else f"<p class='no'><b>No recommendation</b> — {html.escape(plan['why'])}.</p>")
    method = ("<p class='note'>Widths: the Fisher information of the fit's own residual at the noiseless truth, "
              "nuisances (offsets, load-cell zero and its drift) included, averaged over the fit's verdict (undecided, "
              "it reports the hull of both slip conditions' intervals). P(slip decided): the probability that the "
              "fit's ΔBIC exceeds 10 for the true slip (the other slip's misfit to the noiseless curve, spread by the "
              "noise). Hatched: outside the model's domain. See docs/planning.md.</p>")
    style = ("body{font-family:sans-serif;max-width:1200px;margin:1em auto;color:#222}table{border-collapse:collapse;"
             "font-size:12px}td,th{border:1px solid #ccc;padding:2px 5px}tr.rec{background:#ffe9a8}.ok{color:#064}"
             ".no{color:#a30}.note{font-size:12px;color:#555}img{max-width:100%}")
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>adhfit plan</title><style>{style}</style></head>"
            f"<body><h1>Test plan</h1>{head}{verdict}{img}{method}{_series(plan)}<h2>Protocols</h2>{_table(plan)}"
            f"</body></html>")


def write_plan_page(plan: dict, path) -> None:
    """Write :func:`plan_html` to ``path`` (atomically)."""
    write_text(path, plan_html(plan))
