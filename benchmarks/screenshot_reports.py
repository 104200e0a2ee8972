"""Render HTML reports to PNG in a real headless browser (Chromium), to look at them as a person would.

    python benchmarks/screenshot_reports.py OUT/report.html OUT/summary.html --outdir docs/img

Needs Chromium (Debian: ``apt-get install chromium``; it is found as ``chromium``, ``chromium-browser``
or ``google-chrome``).  Each page is rendered at a desktop width; the PNG is then trimmed to the page's
content height and scaled down (``--max-width``) so it stays small enough to commit.
"""
from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

BROWSERS = ("chromium", "chromium-browser", "google-chrome", "chrome")


def find_browser() -> str | None:
    """The path of a Chromium-like browser, or None."""
    return next((p for p in map(shutil.which, BROWSERS) if p), None)


def screenshot(browser: str, html: Path, png: Path, *, width: int = 1300, height: int = 6000) -> Path:
    """Render ``html`` with headless Chromium into ``png`` (full window, trimmed later)."""
    with tempfile.TemporaryDirectory() as profile:
        cmd = [browser, "--headless=new", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
               f"--user-data-dir={profile}", f"--window-size={width},{height}", f"--screenshot={png}",
               html.resolve().as_uri()]
        subprocess.run(cmd, check=True, capture_output=True, timeout=180)
    return png


def trim(png: Path, *, max_width: int = 900, max_height: int = 5000) -> Path:
    """Cut the white space below the content, then scale to ``max_width`` (Pillow)."""
    from PIL import Image, ImageChops  # noqa: PLC0415
    img = Image.open(png).convert("RGB")
    bg = Image.new("RGB", img.size, (255, 255, 255))
    box = ImageChops.difference(img, bg).getbbox()
    if box:
        img = img.crop((0, 0, img.width, min(img.height, box[3] + 20, max_height)))
    if img.width > max_width:
        img = img.resize((max_width, round(img.height * max_width / img.width)), Image.LANCZOS)
    img.quantize(colors=256, method=Image.Quantize.FASTOCTREE).save(png, optimize=True)  # small enough to commit
    return png


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("pages", nargs="+", type=Path, help="HTML files")
    ap.add_argument("--outdir", type=Path, default=Path("docs/img"))
    ap.add_argument("--names", nargs="*", default=None, help="PNG names (default: the HTML stems)")
    ap.add_argument("--max-width", type=int, default=900)
    ap.add_argument("--max-height", type=int, default=5000)
    args = ap.parse_args(argv)
    browser = find_browser()
    if browser is None:
        print("no Chromium found: apt-get install chromium", file=sys.stderr)
        return 2
    args.outdir.mkdir(parents=True, exist_ok=True)
    names = args.names or [p.stem for p in args.pages]
    for page, name in zip(args.pages, names):
        png = args.outdir / f"{name}.png"
        trim(screenshot(browser, page, png), max_width=args.max_width, max_height=args.max_height)
        print(f"{page} -> {png} ({png.stat().st_size // 1024} KiB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
