"""The runtime models against their stored golden outputs (tests/components/golden: regenerated only on purpose by
its regenerate.py). Held to 1e-9 relative: another compiler or target may round differently (fused multiply-add),
a change of the physics moves them far more."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

GOLDEN = Path(__file__).resolve().parent / "golden"
_spec = importlib.util.spec_from_file_location("golden_regenerate", GOLDEN / "regenerate.py")
regenerate = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(regenerate)


@pytest.mark.parametrize("case", list(regenerate.CASES))
def test_outputs_match_the_golden_file(case):
    stored = np.genfromtxt(GOLDEN / f"{case}.csv", delimiter=",", names=True)
    names, values = regenerate.rows(case)
    assert list(stored.dtype.names) == names
    for j, name in enumerate(names):
        want = stored[name]
        np.testing.assert_allclose(values[:, j], want, rtol=1e-9, atol=1e-12 * np.abs(want).max(), err_msg=name)
