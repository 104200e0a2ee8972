"""report.md: the fit result for people — values with units, intervals, the slip verdict, warnings, and
how the data were treated."""
from __future__ import annotations

from pathlib import Path

__all__ = ["render_markdown", "write_markdown"]

_UNITS = {"work_of_adhesion": (1.0, "J/m²"), "mu_h": (1.0, "N/m"), "displacement_offset": (1e6, "µm"),
          "pressure_offset": (1.0, "Pa"), "force_offset": (1e3, "mN")}


def _num(x, digits=4) -> str:
    return "n/a" if x is None else f"{x:.{digits}g}"


def _row(name: str, d: dict) -> str:
    """One table row from a report.json estimate; one-sided and undetermined values say so."""
    from .text import display, estimate_text, interval_text, status_text  # noqa: PLC0415
    sym, _, k, unit = display(name, d.get("unit"))
    status = status_text(d)
    if status != "determined":
        return f"| {sym} ({name}) | {estimate_text(name, d)} | {interval_text(name, d, unit=False)} | {unit} |"
    se = "n/a" if d.get("stderr") is None else f"{d['stderr'] * k:.2g}"
    return (f"| {sym} ({name}) | {d['value'] * k:.5g} ± {se} | {interval_text(name, d, unit=False)} "
            f"({d.get('ci_method') or 'none'}) | {unit} |")


def _how(result) -> str:
    """How the values and intervals were obtained; the method column of the table says it per row."""
    if getattr(result, "provenance", {}).get("method") == "mcmc":
        return ("Values are posterior medians ± posterior standard deviations; 95 % intervals are "
                "posterior percentiles (credible intervals).")
    return ("Values ± standard errors (covariance); 95 % intervals from the likelihood profile where "
            "it converged, else from the covariance.")


def _estimates(result) -> list[str]:
    out = ["## Estimates", "",
           f"Reported fit: **{result.reported_slip}**. " + _how(result), "",
           "| parameter | value ± stderr | 95 % interval | unit |", "|---|---|---|---|"]
    d = result.as_dict()
    out += [_row(n, e) for n, e in {**d.get("parameters", {}), **{k: v for k, v in (d.get("offsets") or {}).items()
                                                                   if isinstance(v, dict)}}.items()]
    fit = result.fits[result.reported_slip]
    out += ["", f"- W_ad–μh correlation: {_num(result.correlation, 3)}",
            f"- reduced χ²: {_num(fit.redchi, 4)} ({fit.ndata} residuals, {fit.nvarys} parameters)",
            f"- force noise σ = {result.sigma * 1e3:.4g} mN, {result.sigma_source}"]
    return out


def _slip(result) -> list[str]:
    s = result.slip
    out = ["## Slip condition", "", f"**{s['verdict']}** (selected: {s['selected'] or 'none'}). "
           + s.get("explanation", ""), "",
           "| slip | χ² | reduced χ² | AIC | BIC | W_ad (J/m²) | μh (N/m) |", "|---|---|---|---|---|---|---|"]
    for name, f in result.as_dict().get("fits", {}).items():
        p = f.get("parameters") or {}
        w, m = (p.get("work_of_adhesion") or {}).get("value"), (p.get("mu_h") or {}).get("value")
        out.append(f"| {name} | {_num(f.get('chisqr'), 5)} | {_num(f.get('redchi'), 4)} | {_num(f.get('aic'), 6)} "
                   f"| {_num(f.get('bic'), 6)} | {_num(w, 5)} | {_num(m, 5)} |")
    out += ["", "Both fits share data and parameter count, so ΔAIC = ΔBIC = Δ(−2 ln L). Scale on ΔBIC: "
            "> 10 decisive (selected), 2–10 favoured with caution (not selected), < 2 no preference. "
            "A single fit's χ² cannot tell the slip condition; only the comparison can."]
    return out


def _treatment(result) -> list[str]:
    seg, line = result.segments, result.curve.line if result.curve is not None else None
    at = (lambda i: f"line {int(line[i])}") if line is not None else (lambda i: f"row {i}")
    jump = ("no detachment jump was found: every unloading row is modelled as attached"
            if seg["i_jump"] is None else
            f"the detachment jump ({seg['jump'] * 1e3:.3g} mN) before {at(seg['i_jump'])}; "
            f"{seg['n_detached']} rows after it are the free membrane (model force zero)")
    out = ["## How the rows were modelled", "",
           f"- {result.n_points} rows used; {result.n_excluded} lines left out (blank or comment lines"
           + (": " + ", ".join(str(n) for n, _ in result.excluded[:20]) if result.excluded else "") + ").",
           f"- Segments by row order, never by value: {seg['n_loading']} loading rows up to {at(seg['i_turn'])} "
           f"(largest control value); {seg['n_attached']} unloading rows while attached; {jump}.",
           "- Loading rows before contact (δ < 0, or p below the contact pressure) have zero model force; "
           "unloading rows beyond the model's turning point but before the measured jump get the "
           "turning-point force (a clamp that keeps the residual continuous).",
           "- The measured pull-off position (midway between the last attached and the first detached row, "
           "σ = spacing/√12) is one more residual against the model's turning point."]
    offsets = result.as_dict().get("offsets") or {}
    for name, e in offsets.items():
        from .text import display, estimate_text  # noqa: PLC0415
        text = estimate_text(name, e) if isinstance(e, dict) else f"{e * display(name)[2]:.4g} {display(name)[3]}"
        out.append(f"- Offset {name}: {text} (added to the measured values).")
    if not offsets:
        out.append("- No offsets were fitted.")
    return out


def seed_text(d: dict) -> str:
    from .text import seed_text as _seed  # noqa: PLC0415
    return _seed(d)


def render_markdown(result) -> str:
    """The human report of a :class:`~adhfit.fitting.result.FitResult` as Markdown."""
    prov = result.provenance
    out = ["# adhfit fit report", "",
           f"Input `{prov.get('input')}` (sha256 `{prov.get('input_sha256', '')[:16]}…`), scene "
           f"`{prov.get('scene_file')}`, method {result.method}, adhfit {prov.get('adhfit_version')}, "
           f"{seed_text(result.as_dict())}.", ""]
    if result.method == "mcmc":
        from .mcmc_markdown import mcmc_sections  # noqa: PLC0415
        out += mcmc_sections(result)
    out += _estimates(result) + [""] + _slip(result) + ["", "## Warnings", ""]
    out += [f"- ⚠ {w}" for w in result.warnings] or ["- none"]
    out += [""] + _treatment(result)
    out += ["", "## Cost", "", f"{result.n_evaluations} model evaluations ({result.n_histories} computed "
            f"histories) in {result.wall_time:.1f} s on the {prov.get('backend')} backend.", "",
            "The model rests on the large-stretch approximation of the membrane (paper eq. 10), validated at "
            "λ0 = 2; λ0 cannot be identified from force curves."]
    return "\n".join(out) + "\n"


def write_markdown(result, path: str | Path) -> Path:
    path = Path(path)
    path.write_text(render_markdown(result), encoding="utf-8")
    return path
