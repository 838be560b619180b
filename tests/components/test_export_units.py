"""The unit systems of an export: a pressure and a velocity in the file's units and back."""

from __future__ import annotations

import pytest

from tribocosim.errors import ParameterError
from tribocosim.components.friction_export.export_units import unit_system


def test_mm_t_s_writes_mpa_and_mm_per_s_and_si_writes_pa_and_m_per_s():
    mm = unit_system("mm-t-s")
    assert (mm.pressure, mm.velocity, mm.length) == ("MPa", "mm/s", "mm")
    assert mm.pressure_to_file(25e6) == pytest.approx(25.0) and mm.velocity_to_file(0.08) == pytest.approx(80.0)
    assert mm.pressure_from_file(mm.pressure_to_file(3.3e6)) == pytest.approx(3.3e6, rel=1e-15)
    assert mm.length_from_file(35.0) == pytest.approx(0.035)
    si = unit_system("SI")
    assert si.pressure_to_file(25e6) == 25e6 and si.velocity_to_file(0.08) == 0.08
    assert "MPa" in mm.header() and "m/s" in si.header()


def test_an_unknown_system_names_the_option():
    with pytest.raises(ParameterError, match="--units 'inch'"):
        unit_system("inch")
