"""The macro sum's single-threaded axpy, and the shared model's drag setting: contraction
inside ``BodyModel.dragging`` only, exact sums outside it whatever came before."""

from __future__ import annotations

import numpy as np
import pytest

from avatar.body import macros
from avatar.body.model import MACRO_GROUP, BodyModel, _axpy


@pytest.fixture(scope="module")
def shared(assets):
    return BodyModel.shared()


def test_axpy_adds_in_place_over_a_range_within_an_ulp():
    rng = np.random.default_rng(3)
    for n in (7, 70_000):  # the second is larger than the first scratch buffer
        x = rng.standard_normal(n).astype(np.float32)
        y = rng.standard_normal(n).astype(np.float32)
        want = y.astype(np.float64)
        want[2 : n - 3] += 0.37 * x[2 : n - 3].astype(np.float64)
        same = y
        _axpy(0.37, x, y, 2, n - 3)
        assert y is same and y.dtype == np.float32  # in place
        assert y[0] == same[0] and np.array_equal(y[n - 3 :], want[n - 3 :].astype(np.float32))
        assert np.abs(y - want).max() <= 2 * np.spacing(np.float32(np.abs(want).max()))
    z = np.ones(5, np.float32)
    _axpy(2.0, np.ones(5, np.float32), z)  # whole vector by default
    assert np.array_equal(z, np.full(5, 3.0, np.float32))


def test_model_has_no_threaded_blas_in_its_sum():
    import avatar.body.model as module

    assert not hasattr(module, "blas")  # OpenBLAS threads cost ms a call on a loaded machine


def _drag(model: BodyModel, group: str, base: dict, steps: int) -> dict:
    values = dict(base)
    for i in range(steps):
        values |= {m: 0.55 + 0.01 * i for m in macros.MACROS if MACRO_GROUP[m] == group}
        model.macro_sum(values)
    return values


def test_shared_model_contracts_only_while_dragging(shared):
    base = {k: d for k, (_, d) in macros.MACROS.items()} | {"gender": 0.3, "age": 0.6}
    with shared.dragging():
        values = _drag(shared, "weight", base, 4)
        con = shared.macro_sum._contraction
        assert con is not None and con.group == "weight"  # the drag used a contraction
        np.testing.assert_allclose(shared.macro_sum(values), shared.macro_sum.full(values),
                                   atol=1e-6)  # fmt: skip
    assert shared.macro_sum.contract is False  # the shared model's setting is back
    # Outside the block the same values (the contraction still memoised) give the exact
    # sum, bit for bit, and a further drag builds no contraction.
    assert np.array_equal(shared.macro_sum(values), shared.macro_sum.full(values))
    values = _drag(shared, "weight", values, 3)
    assert np.array_equal(shared.macro_sum(values), shared.macro_sum.full(values))
    assert shared.macro_sum._contraction is con


def test_dragging_restores_the_setting_after_an_error(shared):
    with pytest.raises(RuntimeError), shared.dragging():
        assert shared.macro_sum.contract is True
        raise RuntimeError("boom")
    assert shared.macro_sum.contract is False
