"""The curves of a test series in a report (report.json ``curves``, docs/contracts.md A7): one row per curve
(its scene, noise, χ² against the shared fit, its own fit, its pull and share of the precision, flags), the
offsets per curve and the contact-radius rows, and the shared interval against the single-curve ones."""
from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from .view import (OFFSET_SENTENCE, Bullets, Note, Section, Table, curve_label, display, estimate_text, fmt,
                   interval_text)

__all__ = ["curves_section", "series_facts", "inputs_table", "rows_facts", "scene_text", "FLAG_WORDS"]

FLAG_WORDS = {"redchi": "misfit: the shared values do not follow it",
              "redchi_contact_radius": "contact radius misfit",
              "pull": "disagrees with the other curves"}
_HEADER = ("#", "curve", "scene", "rows", "force noise σ (mN)", "χ²/n force", "χ²/n contact radius",
           "W_ad alone (J/m², 95 %)", "μh alone (N/m, 95 %)", "pull on W_ad, μh (σ)", "p",
           "share of W_ad, μh precision", "flags")
_LEGEND = ("χ²/n: the curve's own reduced χ² against the shared fit, in units of its row-to-row noise (about 1 when "
           "the curve agrees; flagged above 2).",
           "alone: the curve's own least-squares fit, for comparison.",
           "pull: how far the shared value moves when the curve is left out, in standard errors of the shared value; "
           "p: the chance of a pull this large if the curve agrees with the others (χ², 2 degrees of freedom; "
           "flagged below 0.001).",
           "share of precision: how much of the shared value's precision (1/σ²) the curve brings "
           "(1 − σ²/σ²_without; linearised).")


def scene_text(c: Mapping[str, Any]) -> str:
    """The curve's own scene value: ``P = 0.8 kPa`` (displacement control) or ``gap = 1.2 mm``."""
    sc = c.get("scene") or {}
    if sc.get("control") == "displacement" and sc.get("pressure") is not None:
        return f"P = {fmt(sc['pressure'] * 1e-3)} kPa"
    if sc.get("control") == "pressure" and sc.get("gap") is not None:
        return f"gap = {fmt(sc['gap'] * 1e3)} mm"
    return str(sc.get("control") or "")


def _pct(x: Any) -> str:
    return "n/a" if not isinstance(x, (int, float)) else f"{100 * x:.0f} %"


def _alone(c: Mapping[str, Any], name: str) -> str:
    a = (c.get("alone") or {}).get(name)
    if not isinstance(a, Mapping):
        return "n/a"
    if a.get("status", "determined") != "determined" or a.get("value") is None:
        return estimate_text(name, a)
    return f"{fmt(a['value'])} {interval_text(name, a, unit=False)}"


def _row(k: int, c: Mapping[str, Any]) -> tuple[str, ...]:
    lo = c.get("leave_one_out") or {}
    s, share = lo.get("shift_in_stderr") or {}, lo.get("contribution") or {}
    cr, sf = c.get("contact_radius") or {}, c.get("sigma_force")
    return (str(k + 1), curve_label(c.get("file")), scene_text(c), fmt(c.get("n_points")),
            fmt(None if sf is None else sf * 1e3, 2), fmt(c.get("redchi"), 3),
            fmt(cr.get("redchi"), 3) if cr else "not fitted", _alone(c, "work_of_adhesion"), _alone(c, "mu_h"),
            f"{fmt(s.get('work_of_adhesion'), 2)}, {fmt(s.get('mu_h'), 2)}", fmt(lo.get("p_value"), 2),
            f"{_pct(share.get('work_of_adhesion'))}, {_pct(share.get('mu_h'))}",
            "; ".join(FLAG_WORDS.get(f, f) for f in c.get("flags") or []) or "—")


def _offsets(curves: list) -> Section | None:
    names: list[str] = []
    for c in curves:
        names = list(dict.fromkeys([*names, *(c.get("offsets") or {})]))
    if not names:
        return None
    rows = []
    for k, c in enumerate(curves):
        offs = c.get("offsets") or {}
        rows.append((str(k + 1), *("n/a" if not isinstance(offs.get(n), Mapping) else offs[n].get("note")
                                   or estimate_text(n, offs[n]) for n in names)))
    head = ("#", *(f"{display(n)[0]}, {display(n)[1]}" for n in names))
    return Section("Offsets per curve", (Table(head, tuple(rows), numeric=(0,)), Note((OFFSET_SENTENCE,), "muted")))


def _radius(curves: list) -> Section | None:
    rows = tuple((str(k + 1), fmt(cr.get("n_used")), fmt(cr.get("n_zero_not_in_contact")), fmt(cr.get("n_missing")),
                  fmt((cr.get("sigma") or 0) * 1e6, 3), fmt(cr.get("redchi"), 3))
                 for k, c in enumerate(curves) if (cr := c.get("contact_radius")))
    if not rows:
        return None
    return Section("Contact radius", (Table(("#", "rows used", "of them 0 (not in contact)", "rows missing (skipped)",
                                             "noise σ_a (µm)", "χ²/n"), rows, numeric=(0, 1, 2, 3, 4, 5)),))


def curves_section(d: Mapping[str, Any]) -> Section:
    """The Curves section of a series' report."""
    curves = list(d.get("curves") or [])
    flagged = [k for k, c in enumerate(curves) if c.get("flags")]
    head = (Note(("Every curve agrees with the shared fit.",), "ok") if not flagged else
            Note((f"{len(flagged)} curve(s) flagged: " + ", ".join(curve_label(curves[k].get("file"))
                                                                  for k in flagged) + ". See the warnings.",), "bad"))
    parts = [head, Table(_HEADER, tuple(_row(k, c) for k, c in enumerate(curves)), numeric=tuple(range(3, 12)),
                         flagged=tuple(flagged)),
             Bullets(_LEGEND, "muted"), _offsets(curves), _radius(curves)]
    return Section("Curves", tuple(p for p in parts if p is not None))


def series_facts(d: Mapping[str, Any]) -> list[str]:
    """The shared W_ad interval against the narrowest single-curve one, and how the noise was set."""
    out = []
    w = (d.get("parameters") or {}).get("work_of_adhesion") or {}
    ci = w.get("ci95")
    if ci and None not in ci and w.get("value"):
        widths = []
        for c in d.get("curves") or []:
            a = (c.get("alone") or {}).get("work_of_adhesion") or {}
            aci, v = a.get("ci95"), a.get("value")
            if aci and None not in aci and v:
                widths.append(((aci[1] - aci[0]) / v, curve_label(c.get("file"))))
        shared = (ci[1] - ci[0]) / w["value"]
        if widths:
            best, name = min(widths)
            out.append(f"The shared W_ad interval is {100 * shared:.2g} % of the value wide; the narrowest "
                       f"single-curve interval ({name}) is {100 * best:.2g} %.")
        else:
            out.append(f"The shared W_ad interval is {100 * shared:.2g} % wide; no single curve determines W_ad alone.")
    given = ((d.get("provenance") or {}).get("options") or {}).get("sigma") is not None
    out.append("noise: one σ per curve and observable, " + ("given" if given else "estimated from each curve's "
               "residuals") + " (the force noise of each curve is in the Curves table)")
    return out


def inputs_table(prov: Mapping[str, Any]) -> Table:
    """Every input file of a series with its SHA-256 and scene file."""
    files = list(prov.get("input") or [])
    shas = list(prov.get("input_sha256") or []) + [""] * len(files)
    scenes = list(prov.get("scene_file") or []) + [""] * len(files)
    return Table(("#", "input file", "SHA-256", "scene file"),
                 tuple((str(k + 1), str(f), str(shas[k] or "n/a"), str(scenes[k] or "n/a"))
                       for k, f in enumerate(files)))



def rows_facts(d: Mapping[str, Any]) -> list[str]:
    """Per curve of a series: its rows and where the model puts the jump off the substrate."""
    out = []
    for k, c in enumerate(d.get("curves") or []):
        jump = c.get("first_detached_row")
        out.append(f"curve {k + 1} ({curve_label(c.get('file'))}): {fmt(c.get('n_points'))} rows; "
                   + ("every unloading row modelled as attached (no jump off the substrate in the data)."
                      if jump is None else f"rows from {fmt(jump + 1)} on are after the jump off the substrate "
                                           "(the free membrane, model force zero)."))
    return out
