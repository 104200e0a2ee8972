"""The first run's engine start (adhfit/cli/engine.py): the parts, the second process of a cold start,
the running clock's part and kernel.  No timing here (benchmarks/bench_first_run.py measures it)."""
from __future__ import annotations

import time

import pytest

from adhfit.cli import engine
from adhfit.cli import runners


@pytest.fixture
def cold_markers(tmp_path, monkeypatch):
    """Every part's marker (and the engine's) in a fresh folder: each part looks cold, its kernels are
    still in numba's cache, so 'compiling' them only loads them."""
    monkeypatch.setattr(engine, "_part_marker", lambda part: tmp_path / f"engine-{part}.ready")
    monkeypatch.setattr(engine, "_marker", lambda: tmp_path / "engine.ready")
    return tmp_path


def test_every_part_is_marked_once_warmed(cold_markers):
    assert all(engine.part_is_cold(p) for p in engine.PARTS) and engine.engine_cache_is_cold()
    engine.warm_up("displacement")
    assert not any(engine.part_is_cold(p) for p in engine.PARTS) and not engine.engine_cache_is_cold()


def test_a_cold_start_compiles_the_later_parts_in_a_second_process(cold_markers, monkeypatch):
    started = []
    real = engine.compile_beside

    def spy(parts):
        started.append(list(parts))
        return real(parts)
    monkeypatch.setattr(engine, "compile_beside", spy)
    monkeypatch.setattr(runners, "default_workers", lambda: 2)

    class Progress:
        parts: list[str] = []

        def part(self, label):
            self.parts.append(label)
    progress = Progress()
    engine.warm_up("displacement", progress=progress)
    assert started == [list(engine.PARTS[1:])]  # the first part here, the others beside it
    assert progress.parts[0] == engine.PART_LABELS[engine.PARTS[0]]
    assert any(label.endswith("(second process)") for label in progress.parts)
    engine.warm_up("displacement")  # warm now: no second process
    assert started[-1] == []


def test_one_core_compiles_everything_here(monkeypatch):
    monkeypatch.setattr(runners, "default_workers", lambda: 1)
    assert engine.compile_beside(["exact"]) == {}
    assert engine.compile_beside([]) == {}


def test_an_unknown_part_is_named():
    with pytest.raises(ValueError, match="unknown engine part 'nope'"):
        engine.warm_part("nope")


def test_the_clock_names_the_part_and_the_kernel_compiling(capsys):
    from numba import njit
    clock = engine._CompileClock(enabled=True)
    clock.part("large-stretch")
    clock._kernels._stack.append("history._pinning")  # what numba's compile event would push
    time.sleep(1.2)
    clock._kernels._stack.clear()
    njit(lambda x: x + 1)(1)  # a real compile event passes through the listener without error
    clock.stop()
    err = capsys.readouterr().err
    assert "\radhfit: compiling the engine (once; " in err
    assert " · large-stretch: history._pinning" in err and "done in " in err
