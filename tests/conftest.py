"""Fixtures shared by every test folder."""

from __future__ import annotations

from pathlib import Path

import pytest

#: a component outside the package (tests/components/extra/lagcomponent): a first-order lag
EXTRA_COMPONENTS = Path(__file__).resolve().parent / "components" / "extra"


@pytest.fixture
def lag_component(monkeypatch):
    """The test component ``lag`` (FMU ``Lag``), registered for the test and forgotten after it."""
    from tribocosim.components import registry

    monkeypatch.syspath_prepend(str(EXTRA_COMPONENTS))
    monkeypatch.setattr(registry, "_REGISTERED", dict(registry._REGISTERED))
    from lagcomponent.component import COMPONENT

    return registry.register(COMPONENT)
