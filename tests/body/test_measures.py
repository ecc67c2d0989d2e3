import numpy as np
import pytest

from avatar.body import measures


def test_default_measurements_are_human(model):
    m = measures.measure(model.shape(), model.base)
    assert 1.55 < m["height"] < 1.80
    assert 0.75 < m["chest"] < 1.05 and 0.55 < m["waist"] < 0.85 and 0.8 < m["hips"] < 1.05


@pytest.mark.parametrize("name,param", [("hips", "pca/hips_fat"), ("waist", "pca/belly"),
                                        ("chest", "pca/breast")])  # fmt: skip
def test_girths_grow_with_their_attribute(model, name, param):
    small = measures.measure(model.shape({param: -1.0}), model.base)[name]
    large = measures.measure(model.shape({param: 2.0}), model.base)[name]
    assert large > small + 0.02


def test_fit_reaches_requested_measurements(model):
    want = {"height": 1.80, "chest": 1.0, "waist": 0.85, "hips": 1.0}
    params, got = measures.fit(model, want, {"gender": 1.0})
    for k, v in want.items():
        assert got[k] == pytest.approx(v, abs=0.005)
    again = measures.measure(model.shape(params), model.base)
    assert np.isclose(again["height"], got["height"])


def test_fit_rejects_unknown_measurements(model):
    from avatar.errors import ParameterError

    with pytest.raises(ParameterError):
        measures.fit(model, {"inseam": 0.8})
