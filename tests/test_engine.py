"""The compiled engine's own contracts: failures worded from the kernel's report, the row limit,
and the cache key over all of adhfit/core."""
from __future__ import annotations

import pytest

from adhfit.core import jit
from adhfit.errors import DomainError, InputError
from adhfit.loading import history
from adhfit.params import DIMENSIONLESS

#: a valid scene whose pinning branch leaves the model's domain (found by a scan of extreme scenes:
#: strong adhesion on a small, strongly curved substrate under pressure control at a negative gap)
FAILING = dict(control="pressure", slip="frictionless", d=-0.9, w=5.0, rs=0.05, a_max=0.04)


def test_a_failing_history_names_its_stage_and_inputs():
    with pytest.raises(DomainError) as info:  # the Case I limit (tests/test_domain_limit.py)
        history(**FAILING)
    err = info.value
    assert err.what.startswith("the pinning branch (frictionless) reaches the Case I limit")
    # the failing state and every input of the scene are carried and printed
    for k in ("locator", "kappa", "d", "w", "rs", "a_max", "points"):
        assert k in err.inputs and f"{k}=" in str(err)
    assert 0.0 < err.inputs["locator"] < 1.6  # a contact angle reached on the way


def test_unreachable_loading_end_is_an_input_error_with_the_reachable_range():
    with pytest.raises(InputError) as info:
        history("displacement", "frictionless", p=0.6, w=0.2, rs=0.5, delta_max=1.9)
    assert info.value.name == "delta_max" and "(0, " in str(info.value)


def test_the_row_limit_is_stated_where_the_input_is_read():
    top = int(DIMENSIONLESS["points"].upper)
    with pytest.raises(InputError) as info:
        history("displacement", "no-slip", p=0.6, w=0.2, rs=0.5, a_max=0.25, points=top + 1)
    assert info.value.name == "points" and str(top) in str(info.value)


def test_cache_key_covers_every_core_module(tmp_path, monkeypatch):
    """Any edit in core/ changes the key every kernel's cache is stamped with."""
    before = jit.core_hash()
    assert before == jit.core_hash()
    for name in ("special.py", "history.py"):
        (tmp_path / name).write_text((jit._CORE / name).read_text())
    monkeypatch.setattr(jit, "_CORE", tmp_path)
    one = jit.core_hash()
    (tmp_path / "special.py").write_text((tmp_path / "special.py").read_text() + "\n# edit\n")
    assert jit.core_hash() != one


def test_every_kernel_is_cached_on_the_core_hash():
    """The kernels' numba caches are stamped with the hash of all of core/ (not their own file)."""
    from adhfit.core import history, special  # noqa: PLC0415

    assert jit.KEYED_ON_CORE
    for kernel in (special.carlson_rf, history.run):
        locator = kernel._cache._impl.locator
        assert type(locator).__name__ == "_TreeLocator"
        assert locator.get_source_stamp() == jit.core_hash()


def test_exact_kernels_are_cached_on_the_exact_hash():
    """The exact membrane's kernels are stamped with the hash of all of exact/, not core/'s."""
    from adhfit.exact import jit as exact_jit  # noqa: PLC0415
    from adhfit.exact import kernels  # noqa: PLC0415

    assert exact_jit.KEYED_ON_EXACT
    kernel = next(getattr(kernels, n) for n in dir(kernels) if hasattr(getattr(kernels, n), "_cache"))
    locator = kernel._cache._impl.locator
    assert type(locator).__name__ == "_TreeLocator"
    assert locator.get_source_stamp() == exact_jit.exact_hash() != jit.core_hash()
