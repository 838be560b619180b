"""The strip-draw experiments run in batches (cosim/studies/stripdraw_experiment.py): the warnings of many draws."""

from __future__ import annotations

import warnings

from tribocosim.cosim.studies.stripdraw_experiment import Point, draw, run_points
from tribocosim.errors import RangeWarning


def test_draws_that_fall_below_the_floor_alike_are_warned_once_with_their_number():
    """Three draws of the paper's model (frictionless flakes, the closed-form law, whose cap of beta the first pass
    reaches) at three pressures each fall below the documented floor, each model at its own time and mu: the batch
    gives one warning, the first draw's, saying how many of the draws warned so; a draw that stays above it adds
    nothing."""
    paper = {"friction_model": "closed_form", "flake_shear_ratio": 0.0, "draw_length": 0.03}
    points = [Point(p, 0.035, 1, paper) for p in (9e6, 10e6, 11e6)]
    points.append(Point(10e6, 0.035, 1, {**paper, "flake_shear_ratio": 0.2}))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = run_points(points, workers=1, fn=draw)
    assert len(out) == 4 and all(len(o) == 1 for o in out)
    floor = [str(w.message) for w in caught if issubclass(w.category, RangeWarning)]
    assert len(floor) == 1, floor
    assert floor[0].startswith("StripDrawModel: at t = ") and "flake_shear_ratio = 0 with mu0 = 0.15" in floor[0]
    assert floor[0].endswith("(the first of 3 of the 4 draws that warned so)"), floor[0]
