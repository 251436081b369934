"""The small numeric helpers against numpy's own definitions."""

import numpy as np
import pytest

from visemeface.numeric import quantile


@pytest.mark.parametrize("dtype", [np.float32, np.float64, np.int64, np.uint8])
@pytest.mark.parametrize("n", [1, 2, 3, 10, 301])
def test_quantile_is_numpys_linear_percentile(dtype, n):
    rng = np.random.default_rng(n)
    a = (rng.random(n) * 200).astype(dtype)
    for q in (0.0, 0.05, 0.5, 0.8, 0.9, 1.0):
        assert quantile(a, q) == pytest.approx(float(np.percentile(a, 100 * q)), rel=1e-6, abs=1e-9)
    assert quantile(a, 0.5) == pytest.approx(float(np.median(a)), rel=1e-6, abs=1e-9)


def test_quantile_leaves_its_input_unsorted_and_refuses_nothing_to_measure():
    a = np.array([3.0, 1.0, 2.0])
    assert quantile(a, 0.5) == 2.0
    assert a.tolist() == [3.0, 1.0, 2.0]
    with pytest.raises(ValueError, match="empty"):
        quantile(np.zeros(0), 0.5)


def test_the_examples_in_the_docstrings_hold():
    import doctest

    import visemeface.numeric

    result = doctest.testmod(visemeface.numeric)
    assert result.attempted >= 4 and result.failed == 0
