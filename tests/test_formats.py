"""The file-format registry (adhfit.readers.FORMATS) and Excel workbooks read through it.

Workbooks are built here with openpyxl the way testing software lays them out: metadata rows above
the header, units in the header or in a units row, several sheets (a results summary and the data).
"""
from __future__ import annotations

import ast
import re
from pathlib import Path

import numpy as np
import pytest

from adhfit.data import read_curve
from adhfit.errors import DataError, InputError
from adhfit.readers import FORMATS, Format, find_format, folder_patterns
from adhfit.readers.text import Table, decode, text_layout

openpyxl = pytest.importorskip("openpyxl")

PACKAGE = Path(__file__).resolve().parent.parent / "adhfit"
N = 15
X_MM = np.r_[np.linspace(0.0, 0.4, N), np.linspace(0.38, 0.1, N)]
F_N = np.r_[np.linspace(0.0, 2.0, N), np.linspace(1.8, -0.5, N)]


def _book(path: Path, sheets: dict[str, list[list]]) -> Path:
    wb = openpyxl.Workbook()
    wb.remove(wb.active)
    for name, rows in sheets.items():
        ws = wb.create_sheet(name)
        for row in rows:
            ws.append(list(row))
    wb.save(path)
    return path


def _data_rows(header=("Time", "Extension", "Load"), units=("(s)", "(mm)", "(N)"), meta=True) -> list[list]:
    rows = [["Sample", "A1"], ["Test date", "2026-12-04"], ["Rate", 5, "mm/min"], []] if meta else []
    rows += [list(header)] + ([list(units)] if units else [])
    return rows + [[0.5 * i, float(x), float(f)] for i, (x, f) in enumerate(zip(X_MM, F_N))]


# ---------------------------------------------------------------------------------------------
# the registry
def test_every_format_entry_is_complete():
    suffixes = [s for f in FORMATS.values() for s in f.suffixes]
    assert len(suffixes) == len(set(suffixes)), "a suffix belongs to two formats"
    for key, fmt in FORMATS.items():
        assert isinstance(fmt, Format) and fmt.name and fmt.suffixes, key
        assert all(s.startswith(".") and s == s.lower() for s in fmt.suffixes), key
        assert callable(fmt.tables) and callable(fmt.layout), key


@pytest.mark.parametrize("name, head, expected", [
    ("a.csv", b"time [s],force [mN]\n", "text"),
    ("a.txt", b"x\ty\n", "text"),
    ("a.unknown", b"x,y\n", "text"),
    ("a.lvm", b"anything", "lvm"),
    ("a.txt", b"LabVIEW Measurement\t\nWriter_Version\t2\n", "lvm"),
    ("a.csv", b"PK\x03\x04rest-of-zip", "xlsx"),  # content beats the name
    ("a.XLSX", b"PK\x03\x04", "xlsx"),
    ("a.xls", b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1....", "xls"),
])
def test_a_file_is_found_by_content_then_name(name, head, expected):
    assert find_format(name, head) is FORMATS[expected]


def test_folder_patterns_come_from_the_registry():
    patterns = folder_patterns()
    assert {"*.csv", "*.tsv", "*.lvm", "*.xlsx"} <= set(patterns)
    assert "*.txt" not in patterns and "*.xls" not in patterns


def test_a_toy_format_is_one_registry_entry(tmp_path, monkeypatch):
    """A pipe-separated format with a '%' comment preamble: one entry, found by suffix and by sniff."""

    def tables(raw: bytes, where: str) -> list[Table]:
        lines, _ = decode(raw, where)
        return [Table(where=where, lines=[ln.replace("|", ",") for ln in lines if not ln.startswith("%")],
                      note="toy pipes")]

    toy = Format(name="toy", suffixes=(".pipe",), tables=tables, layout=text_layout,
                 sniff=lambda head: head.startswith(b"%TOY"))
    monkeypatch.setitem(FORMATS, "toy", toy)
    body = "displacement [mm]|force [N]\n" + "".join(f"{x}|{f}\n" for x, f in zip(X_MM, F_N))
    by_suffix = tmp_path / "a.pipe"
    by_suffix.write_text(body)
    by_sniff = tmp_path / "b.dat"
    by_sniff.write_text("%TOY v1\n" + body)
    for path in (by_suffix, by_sniff):
        c = read_curve(path, "displacement")
        assert "toy pipes" in c.layout
        np.testing.assert_allclose(c.x, X_MM * 1e-3)
        np.testing.assert_allclose(c.force, F_N)
    assert "*.pipe" in folder_patterns()


_SUFFIX = re.compile(r"^\*?\.(csv|tsv|txt|lvm|xlsx|xlsm|xls)$", re.IGNORECASE)
#: Modules outside adhfit/readers that still list suffixes themselves, each to switch to
#: ``adhfit.readers.folder_patterns()``: the command line is being rewritten on another branch.
STILL_LISTING: set[str] = set()


def test_no_module_outside_the_registry_lists_file_suffixes():
    """Only adhfit/readers/formats.py names the suffixes of curve files ('.csv', '*.lvm', ...)."""
    found = set()
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE.parent).as_posix()
        if rel == "adhfit/readers/formats.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and _SUFFIX.match(node.value):
                found.add(rel)
    assert found <= STILL_LISTING, sorted(found - STILL_LISTING)


# ---------------------------------------------------------------------------------------------
# Excel workbooks
def test_a_bluehill_like_workbook_reads_without_flags(tmp_path):
    path = _book(tmp_path / "bluehill.xlsx", {"Results": [["Specimen", "Maximum Load (N)"], [1, 2.0]],
                                               "Raw Data": _data_rows()})
    c = read_curve(path, "displacement")
    np.testing.assert_allclose(c.x, X_MM * 1e-3)
    np.testing.assert_allclose(c.force, F_N)
    np.testing.assert_allclose(c.time, 0.5 * np.arange(2 * N))
    assert c.line[0] == 7  # the sheet's row numbers: 4 metadata rows, header, units row
    assert (1, "metadata above the header") in c.excluded and (6, "units row") in c.excluded
    assert c.columns == {"time": "Time", "displacement": "Extension", "force": "Load"}
    assert "Excel workbook" in c.layout and "sheet 'Raw Data'" in c.layout
    assert c.path == str(path)


def test_units_in_the_header_cells_and_no_metadata(tmp_path):
    path = _book(tmp_path / "clean.xlsx", {"Sheet1": _data_rows(("time [s]", "displacement [um]", "force [mN]"),
                                                                units=None, meta=False)})
    c = read_curve(path, "displacement")
    np.testing.assert_allclose(c.x, X_MM * 1e-6)
    np.testing.assert_allclose(c.force, F_N * 1e-3)


def test_header_cells_with_line_breaks_and_clock_times(tmp_path):
    """Excel headers often wrap the unit onto a second line of the cell ('Load\n(N)'); a time column
    formatted as a clock time is optional, so it is left out and listed."""
    import datetime as dt
    rows = [["Time", "Extension\n(mm)", "Load\r\n(N)"]]
    rows += [[dt.time(0, 0, i), float(x), float(f)] for i, (x, f) in enumerate(zip(X_MM, F_N))]
    c = read_curve(_book(tmp_path / "wrapped.xlsx", {"Data": rows}), "displacement")
    assert c.columns == {"displacement": "Extension (mm)", "force": "Load (N)"}
    assert c.time is None and c.ignored_columns[0][0] == "Time"
    np.testing.assert_allclose(c.force, F_N)


def test_an_xlsx_named_csv_is_still_a_workbook(tmp_path):
    path = _book(tmp_path / "export.xlsx", {"Data": _data_rows()})
    renamed = path.rename(tmp_path / "export.csv")
    assert "Excel workbook" in read_curve(renamed, "displacement").layout


def test_several_curve_sheets_name_them_and_sheet_chooses(tmp_path):
    path = _book(tmp_path / "two.xlsx", {"Specimen 1": _data_rows(), "Specimen 2": _data_rows()})
    with pytest.raises(DataError, match=r"2 sheets hold the columns of a curve \('Specimen 1', 'Specimen 2'\)"):
        read_curve(path, "displacement")
    c = read_curve(path, "displacement", sheet="Specimen 2")
    assert "sheet 'Specimen 2'" in c.layout
    with pytest.raises(InputError, match=r"'sheet'.*one of 'Specimen 1', 'Specimen 2'"):
        read_curve(path, "displacement", sheet="Specimen 3")


def test_no_curve_sheet_names_each_sheet_and_why(tmp_path):
    path = _book(tmp_path / "summary.xlsx", {"Results": [["Specimen", "Maximum Load (N)"], [1, 2.0]],
                                              "Notes": [["operator", "JS"]]})
    with pytest.raises(DataError) as err:
        read_curve(path, "displacement")
    msg = str(err.value)
    assert "no sheet holds the columns of a curve under displacement control" in msg
    assert "sheet 'Results'" in msg and "sheet 'Notes'" in msg and "\n" not in msg


def test_the_one_sheet_gives_its_own_error(tmp_path):
    rows = _data_rows()
    rows[10][2] = "#DIV/0!"
    path = _book(tmp_path / "bad.xlsx", {"Data": rows})
    with pytest.raises(DataError, match=r"bad.xlsx, sheet 'Data', line 11, column 'Load': '#DIV/0!' is not a number"):
        read_curve(path, "displacement")


def test_sheet_is_refused_for_a_text_file(tmp_path):
    path = tmp_path / "a.csv"
    path.write_text("displacement [mm],force [N]\n" + "".join(f"{x},{f}\n" for x, f in zip(X_MM, F_N)))
    with pytest.raises(InputError, match="'sheet'.*workbook"):
        read_curve(path, "displacement", sheet="Data")


@pytest.mark.parametrize("content, match", [
    (b"PK\x03\x04" + b"\x00" * 40, "not a readable Excel workbook"),
    (b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1" + b"\x00" * 100, r"Excel 97-2003 workbook \(.xls\).*save it as .xlsx or CSV"),
    (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR", "a binary file, not a text export"),
])
def test_files_that_are_not_text_or_a_workbook_are_named(tmp_path, content, match):
    path = tmp_path / "curve.csv"
    path.write_bytes(content)
    with pytest.raises(DataError, match=match) as err:
        read_curve(path, "displacement")
    assert "PK\\x03" not in str(err.value) and "missing column" not in str(err.value)


def test_a_zip_that_is_not_a_workbook(tmp_path):
    import zipfile
    path = tmp_path / "curve.xlsx"
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("word/document.xml", "<w/>")
    with pytest.raises(DataError, match="a zip archive, but not an Excel workbook"):
        read_curve(path, "displacement")


def test_a_workbook_of_empty_sheets(tmp_path):
    path = _book(tmp_path / "empty.xlsx", {"Sheet1": [], "Sheet2": [[None, None]]})
    with pytest.raises(DataError, match=r"the workbook's sheets are empty \('Sheet1', 'Sheet2'\)"):
        read_curve(path, "displacement")


def test_a_sheet_with_an_empty_data_cell_names_its_row(tmp_path):
    rows = _data_rows()
    rows[9][1] = None
    path = _book(tmp_path / "gap.xlsx", {"Data": rows})
    with pytest.raises(DataError, match=r"sheet 'Data', line 10, column 'Extension': empty cell"):
        read_curve(path, "displacement")
