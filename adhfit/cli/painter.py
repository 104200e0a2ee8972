"""fit.png drawn by a second process while the first one fits.

A one-file ``adhfit fit`` spends about a second on matplotlib (its import, then drawing fit.png) after
the fit, on a machine whose other core idles.  :class:`Painter` starts ``python -m
adhfit.cli.painter`` at the beginning of the run: that process imports matplotlib and the figure
code while the fit runs, then draws :func:`adhfit.report.fit_plot.draw_fit` from the JSON view
(:func:`adhfit.report.fit_plot.fit_view`) it is sent.  The
figure is the same as one drawn in-process (one drawing function); if the painter cannot start or
fails, :meth:`Painter.finish` says so and the caller draws the figure itself.

Protocol (one line each way): the parent writes ``{"view": ..., "path": ...}`` as JSON and closes
standard input; the painter answers ``ok`` or ``error: <reason>`` on standard output and exits.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

__all__ = ["Painter"]


class Painter:
    """A process that draws one fit.png (module docstring)."""

    def __init__(self) -> None:
        root = str(Path(__file__).resolve().parent.parent.parent)  # this adhfit, whatever is installed
        env = os.environ | {"PYTHONPATH": os.pathsep.join(filter(None, (root, os.environ.get("PYTHONPATH"))))}
        try:
            self._proc: subprocess.Popen | None = subprocess.Popen(
                [sys.executable, "-m", "adhfit.cli.painter"], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                stderr=subprocess.DEVNULL, env=env, text=True)
        except OSError:
            self._proc = None
        self._sent = False

    def paint(self, view: dict[str, Any], path: str | Path) -> None:
        """Send the figure's data (:func:`adhfit.report.fit_plot.fit_view`) and where to save it; returns at once."""
        if self._proc is None:
            return
        try:
            self._proc.stdin.write(json.dumps({"view": view, "path": str(path)}) + "\n")
            self._proc.stdin.close()
            self._proc.stdin = None  # sent and closed: communicate() only reads the answer
            self._sent = True
        except (OSError, ValueError):
            self._sent = False

    def finish(self, timeout: float = 120.0) -> bool:
        """Wait for the figure; True when the painter saved it (else the caller draws it)."""
        if self._proc is None:
            return False
        if not self._sent:
            self.close()
            return False
        try:
            out, _ = self._proc.communicate(timeout=timeout)
        except (subprocess.TimeoutExpired, OSError, ValueError):
            self.close()
            return False
        return self._proc.returncode == 0 and out.strip() == "ok"

    def close(self) -> None:
        """Stop the painter (nothing to draw, or the run ended early)."""
        if self._proc is not None and self._proc.poll() is None:
            self._proc.kill()
            self._proc.wait()


def _serve() -> int:
    from ..report.fit_plot import draw_fit  # noqa: PLC0415 - the slow imports, done while the parent fits
    from ..report.plots import file_figure  # noqa: PLC0415
    file_figure()  # matplotlib's figure machinery loaded and warm
    line = sys.stdin.readline()
    if not line.strip():
        return 0  # the parent had nothing to draw
    try:
        job = json.loads(line)
        draw_fit(job["view"], path=job["path"])
    except Exception as err:  # noqa: BLE001 - the parent draws the figure itself and never shows this
        sys.stdout.write(f"error: {type(err).__name__}: {err}\n")
        return 1
    sys.stdout.write("ok\n")
    return 0


if __name__ == "__main__":
    sys.exit(_serve())
