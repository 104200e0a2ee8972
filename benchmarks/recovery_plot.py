"""The recovery study's figure: coverage and bias against noise (``recovery.py``; notebook 04)."""
from __future__ import annotations

from pathlib import Path

import matplotlib

import recovery_stats as rs

LABEL = {"work_of_adhesion": "W_ad", "mu_h": "μh"}


def _band(ax, cells: list[dict], name: str) -> None:
    """Grey: the central 95 % range of the covering fraction of calibrated intervals at each noise's n."""
    by_noise: dict[float, int] = {}
    for c in cells:
        by_noise[c["noise"]] = max(by_noise.get(c["noise"], 0), c[name]["claims"])
    xs = sorted(k for k, n in by_noise.items() if n)
    if not xs:
        return
    lo, hi = zip(*(rs.band(by_noise[x]) for x in xs))
    ax.fill_between([100 * x for x in xs], lo, hi, color="0.85", step="mid",
                    label="95 % range of calibrated coverage (n at that noise)")
    ax.axhline(0.95, color="0.5", ls="--", lw=0.8)


def plot(out: dict, path: Path | None = None):
    """Rows: coverage, bias (± scatter); columns: W_ad, μh.  Clean curves per case and slip, other
    variants (pooled over cases) as markers.  Returns the figure; saved when ``path`` is given."""
    if path is not None:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415
    clean = [c for c in out["cells"] if c["variant"] == "clean"]
    others = [c for c in out["pooled"] if c["variant"] != "clean"]
    fig, axes = plt.subplots(2, 2, figsize=(13, 8.5), layout="constrained", sharex=True)
    for j, name in enumerate(rs.PARAMS):
        _band(axes[0, j], clean, name)
        for key in dict.fromkeys((c["case"], c["slip"]) for c in clean):
            g = sorted((c for c in clean if (c["case"], c["slip"]) == key), key=lambda c: c["noise"])
            x = [100 * c["noise"] for c in g]
            style = {"marker": "o" if key[1] == "no-slip" else "s", "ls": "-" if "curved" in key[0] else ":"}
            axes[0, j].plot(x, [c[name]["coverage"] for c in g], label=f"{key[0]}, {key[1]}", **style)
            axes[1, j].errorbar(x, [100 * (c[name]["bias"] or 0) for c in g], capsize=2,
                                yerr=[100 * (c[name]["scatter"] or 0) for c in g], **style)
        for c, m in zip(others, "^v<>Dph"):
            kw = {"marker": m, "ls": "none", "ms": 9, "mfc": "none"}
            axes[0, j].plot([100 * c["noise"]], [c[name]["coverage"]], label=f"{c['variant']} (pooled)", **kw)
            axes[1, j].plot([100 * c["noise"]], [100 * (c[name]["bias"] or 0)], **kw)
        axes[0, j].set(ylabel=f"{LABEL[name]}: coverage of the 95 % claim", ylim=(-0.02, 1.02), xscale="log",
                       title=f"{LABEL[name]} coverage")
        axes[1, j].axhline(0, color="0.5", lw=0.6)
        axes[1, j].set(xlabel="force noise σ (% of the peak force)", ylabel=f"{LABEL[name]} bias ± sd (%)",
                       title=f"{LABEL[name]} bias (mean relative error) ± scatter")
    ticks = sorted({100 * c["noise"] for c in out["cells"]})
    for ax in axes.flat:
        ax.set_xticks(ticks, [f"{t:g}" for t in ticks])
        ax.minorticks_off()
    axes[0, 0].legend(fontsize=6, ncol=2, loc="lower left")
    p = out["provenance"]
    fig.suptitle(f"Parameter recovery ({out['settings']['method']}), commit {p['commit']}: "
                 f"{len(out['replicates'])} fits", fontsize=10)
    if path is not None:
        fig.savefig(path, dpi=110)
        plt.close(fig)
    return fig
