"""One report dict, one writer per format (issue 19 item 3), offsets described as computed (issue 23 item 4),
files written atomically (item 6), hostile file names shown as text and linked safely (item 7).

Checked on report dictionaries built here (no fit needed), except the atomic-write test, which writes the
reports of a real (small) fit."""
from __future__ import annotations

import copy
import os
import re
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

from adhfit.report.files import relative_link, save_figure, write_atomic, write_text
from adhfit.report.html import render_html
from adhfit.report.markdown import md_escape, render_markdown
from adhfit.report.summary_html import render_summary_html
from adhfit.report.view import OFFSET_SENTENCE
from tests.test_report_html_structure import _mcmc_report, _trust_report

ROOT = Path(__file__).resolve().parents[1]
HOSTILE = ["javascript:alert(3).csv", "a`b`c.csv", "<script>alert(1)</script>.csv", "x|y|z.csv",
           "[click](javascript:alert(2)).csv", 'q"uote\' & <b>.csv']


def _series_report(files=("p800/curve.csv", "p1200/curve.csv")) -> dict:
    d = _trust_report()
    est = {"value": 3e-5, "stderr": 4e-7, "unit": "m"}
    d["curves"] = [{"file": f, "offsets": {"displacement": est, "force": {"value": -2e-6, "stderr": 3e-6, "unit": "N"}},
                    "redchi": 0.9 + k, "n_points": 120, "sigma_force": 3e-5,
                    "scene": {"control": "displacement", "pressure": 800.0 + 400 * k},
                    "leave_one_out": {"shift_in_stderr": {"work_of_adhesion": 0.5, "mu_h": -0.2}, "p_value": 0.3,
                                      "contribution": {"work_of_adhesion": 0.4, "mu_h": 0.5}},
                    "flags": ["pull"] if k else []} for k, f in enumerate(files)]
    d["offsets"] = {"displacement": {"status": "per_curve", "values": [3e-5] * len(files), "unit": "m"}}
    d["provenance"] = {**d["provenance"], "input": list(files), "input_sha256": ["b" * 64] * len(files),
                       "scene_file": ["scene.toml"] * len(files), "scene": None}
    d["segments"] = {}
    return d


def _series_mcmc_report() -> dict:
    d = _mcmc_report()
    s = _series_report()
    d.update(curves=s["curves"], offsets=s["offsets"], provenance={**s["provenance"], "seed": 5, "method": "mcmc"})
    return d


class _Headings(HTMLParser):
    def __init__(self):
        super().__init__()
        self.out, self._in = [], None

    def handle_starttag(self, tag, attrs):
        if re.fullmatch(r"h[1-6]", tag):
            self._in = int(tag[1])
            self.out.append([self._in, ""])

    def handle_endtag(self, tag):
        if re.fullmatch(r"h[1-6]", tag):
            self._in = None

    def handle_data(self, data):
        if self._in:
            self.out[-1][1] += data


def _html_headings(page: str) -> list[tuple[int, str]]:
    p = _Headings()
    p.feed(page)
    return [(lvl, text) for lvl, text in p.out]


def _md_headings(text: str) -> list[tuple[int, str]]:
    out = []
    for line in text.splitlines():
        m = re.match(r"^(#{1,6}) (.*)$", line)
        if m:
            out.append((len(m.group(1)), re.sub(r"\\(.)", r"\1", m.group(2))))
    return out


@pytest.mark.parametrize("make", [_trust_report, _mcmc_report, _series_report, _series_mcmc_report])
def test_markdown_and_html_render_the_same_sections(make):
    d = make()
    h, m = _html_headings(render_html(d)), _md_headings(render_markdown(d))
    assert h == m and len(h) >= 7
    titles = [t for _, t in h]
    series, mcmc = "curves" in d, "mcmc" in d
    assert ("Curves" in titles) == series and ("Bayesian fit (MCMC)" in titles) == mcmc
    assert ("Priors" in titles) == mcmc and ("Slip condition: evidence" in titles) == mcmc
    assert ("Offsets per curve" in titles) == series and ("Offsets (nuisance parameters)" in titles) == (not series)
    for always in ("Warnings", "Plots", "How the rows were used", "Provenance", "Solver details"):
        assert always in titles, always


@pytest.mark.parametrize("make", [_trust_report, _series_report])
def test_offsets_are_described_as_computed_once_in_every_format(make):
    d = make()
    page, md = render_html(d), render_markdown(d)
    assert page.count(OFFSET_SENTENCE.replace("'", "&#x27;")) == 1
    assert md.count(md_escape(OFFSET_SENTENCE)) == 1
    assert "added to the model force" in OFFSET_SENTENCE and "predicted force = model force + F_0" in OFFSET_SENTENCE
    for text in (page, md):
        assert "added to the measured values" not in text


def test_no_report_source_or_doc_describes_the_force_offset_backwards():
    """The sign sentence lives in the view layer once; nothing else says offsets are added to the data."""
    texts = {p: p.read_text(encoding="utf-8") for p in [*(ROOT / "adhfit" / "report").glob("*.py"),
                                                        ROOT / "docs" / "reports.md"]}
    assert [p.name for p, t in texts.items() if "added to the measured values" in t] == []
    assert sum("predicted force = model force + F_0" in t for t in texts.values()) >= 2  # view.py and the doc


@pytest.mark.parametrize("name", HOSTILE)
def test_hostile_file_names_are_text_in_markdown(name):
    d = _series_report(files=(f"dir/{name}", "ok/curve.csv"))
    d["warnings"] = [f"curve {name} disagrees"]
    md = render_markdown(d)
    assert "<script>" not in md and "<b>" not in md
    assert not re.search(r"(?<!\\)`", md), "an unescaped backtick opens code"
    assert not re.search(r"(?<!\\)\]\(", md.replace("](fit.png)", "")), "a Markdown link from a file name"
    # every table row of the curves table has as many cells as its header: no pipe escaped the cell
    for block in re.findall(r"(\| # \| curve.*?)\n\n", md, flags=re.S):
        counts = {len(re.split(r"(?<!\\)\|", row)) for row in block.splitlines()}
        assert len(counts) == 1, block


@pytest.mark.parametrize("name", HOSTILE)
def test_hostile_file_names_are_text_in_html(name):
    for d in (_trust_report(), _series_report(files=(f"dir/{name}", "ok/curve.csv"))):
        d["provenance"]["input"] = f"dir/{name}" if isinstance(d["provenance"]["input"], str) else \
            d["provenance"]["input"]
        page = render_html(d)
        assert "<script>" not in page and "<b>.csv" not in page
        assert not re.search(r"""(href|src)\s*=\s*["']?\s*javascript:""", page, re.I)


def test_relative_link_never_carries_a_scheme(tmp_path):
    for name in HOSTILE + ["http:evil", "file:x", "#frag", "?q=1", "a b.csv"]:
        link = relative_link(tmp_path / name / "report.html", tmp_path)
        parts = urlsplit(link)
        assert parts.scheme == "" and parts.netloc == "" and parts.query == "" and parts.fragment == "", link
        assert unquote(link) == f"{name}/report.html" and not link.startswith("/")
        assert not set(link) & set("\"'<>` |[]()")


def test_summary_page_links_a_hostile_name_as_a_relative_encoded_link(tmp_path):
    from tests.test_report_html_structure import _batch
    rows = _batch(tmp_path)
    evil = tmp_path / "javascript:alert(3)"
    (tmp_path / "c0").rename(evil)
    rows[0] = {**rows[0], "file": str(tmp_path / "data" / "javascript:alert(3).csv"), "report_dir": str(evil)}
    page = render_summary_html(rows, tmp_path)
    hrefs = re.findall(r'href="([^"]*)"', page)
    assert "javascript%3Aalert%283%29/report.html" in hrefs
    assert all(urlsplit(h).scheme == "" for h in hrefs)


def test_atomic_write_leaves_the_old_file_when_interrupted(tmp_path):
    path = write_text(tmp_path / "report.json", "old\n")

    def half(f):
        f.write(b"{\"trunc")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        write_atomic(path, half)
    assert path.read_text() == "old\n" and sorted(p.name for p in tmp_path.iterdir()) == ["report.json"]


def test_a_figure_is_saved_atomically(tmp_path):
    from matplotlib.figure import Figure
    fig = Figure()
    fig.subplots().plot([0, 1], [1, 0])
    (tmp_path / "fit.png").write_bytes(b"old")

    class Broken:
        def savefig(self, f, **kw):
            fig.savefig(f, **kw)
            raise OSError("disk full")

    with pytest.raises(OSError):
        save_figure(Broken(), tmp_path / "fit.png")
    assert (tmp_path / "fit.png").read_bytes() == b"old" and len(list(tmp_path.iterdir())) == 1
    save_figure(fig, tmp_path / "fit.png", dpi=50)
    assert (tmp_path / "fit.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_every_file_report_write_puts_down_is_renamed_into_place(tmp_path, monkeypatch):
    """report.write of a real fit: each file it returns arrives by os.replace from a temporary file of the
    same folder (an interrupted run leaves the old file or the new one, never part of one)."""
    import adhfit
    import adhfit.report.files as files
    from adhfit.report import write
    sample = ROOT / "sample_data" / "fea_displacement_no-slip"
    result = adhfit.fit(sample / "curve.csv", sample / "scene.toml", slip="no-slip", profile=False)
    moved = []
    real = os.replace

    def spy(src, dst):
        moved.append((Path(src), Path(dst)))
        real(src, dst)

    monkeypatch.setattr(files.os, "replace", spy)
    written = write(result, tmp_path / "out")
    assert {p.name for p in written} == {"report.json", "report.md", "report.html", "plot_data.json", "fit.png"}
    assert {dst for _, dst in moved} == set(written)
    assert all(src.parent == dst.parent and src.name.startswith(f".{dst.name}.") for src, dst in moved)
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == sorted(p.name for p in written)
    md = (tmp_path / "out" / "report.md").read_text(encoding="utf-8")
    assert "](fit.png)" in md and md_escape(OFFSET_SENTENCE) in md


def test_a_deep_copy_renders_the_same(tmp_path):
    """The writers read the dict and never change it (a saved report.json renders the same)."""
    d = _series_mcmc_report()
    before = copy.deepcopy(d)
    render_html(d)
    render_markdown(d)
    assert d == before


def test_a_series_per_curve_offset_has_its_symbol_unit_and_curve():
    from adhfit.report.view import display
    assert display("force_offset_1") == ("F_0 [2]", "load-cell zero (force offset) of curve 2", 1e3, "mN")
    assert display("displacement_offset_0")[2:] == (1e6, "µm")
    assert display("mystery_3") == ("mystery_3", "mystery 3", 1.0, "")
