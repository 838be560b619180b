"""How ``surrogate verify`` compares a rerun with a recorded case: exactly only when the same mesoscale code ran on the
same numerics (processor and numerical libraries), within the ensemble's tolerance otherwise."""

from __future__ import annotations

from tribocosim.surrogate.campaign import numerics, run_case
from tribocosim.surrogate.verify import comparison


def test_a_rerun_is_held_to_the_bit_only_by_the_same_code_on_the_same_numerics():
    here = numerics()
    assert comparison(["abc"], "abc", [here], here)[0] == "exact"
    mode, reason = comparison(["abc"], "abc", ["x86_64, skylake-avx512, numpy 2.0.0, numba 0.60.0, pyFFTW 0.14.0"],
                              here)
    assert mode == "tolerance" and "another processor or build of the numerical libraries" in reason
    mode, reason = comparison(["abc"], "abc", [], here)  # a table that records no numerics for its cases
    assert mode == "tolerance" and "are not recorded" in reason
    assert comparison(["abc"], "def", [here], here)[0] == "tolerance"


def test_every_case_records_the_numerics_it_ran_on():
    out = run_case({"case_id": "x", "config": {"n": 1}})  # refused by the slide's checks: recorded all the same
    assert out["status"] == "failed" and out["numerics"] == numerics()
    assert numerics().split(", ")[2].startswith("numpy ")
