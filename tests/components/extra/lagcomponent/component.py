"""The description of the test lag component: all the project needs to build, check and run it."""

from __future__ import annotations

from tribocosim.components.description import Built, Component, Port

from lagcomponent.model import LagParameters


def build(params, files, resources):
    from lagcomponent.model import LagModel

    return Built(LagModel(params))


COMPONENT = Component(
    name="lag",
    model_identifier="Lag",
    summary="First-order lag (a test component from outside the package)",
    parameters=LagParameters,
    inputs=(Port("u", "N", "input signal"),),
    outputs=(Port("y", "N", "lagged, amplified signal"),),
    build=build,
)
