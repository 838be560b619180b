"""Component.split (components/description.py): a parameter dict made into the component's dataclasses, unknown
names refused; every packaged scene's component FMUs split as they are written."""

from __future__ import annotations

import pytest

from tribocosim.components import registry
from tribocosim.components.stripdraw.component import COMPONENT
from tribocosim.errors import ParameterError


def test_split_refuses_unknown_names_and_keeps_inputs_out_of_the_parameters():
    params, files = COMPONENT.split({"tool_length": 0.07, "table_file": "t.npz", "normal_force": 24500.0})
    assert params.tool_length == 0.07 and files.table_file == "t.npz"
    with pytest.raises(ParameterError) as err:
        COMPONENT.split({"tool_lenght": 0.07, "pull_force": 1.0})
    message = str(err.value)
    assert "'tool_lenght' (did you mean 'tool_length'?)" in message and "'pull_force' is an output" in message, message
    assert "allowed: the parameters" in message and "the inputs grip_velocity, normal_force" in message, message
    with pytest.raises(ParameterError, match="unknown parameter 'n_nodes'"):
        COMPONENT.make({"n_nodes": 41})  # the FMI 3.0 FMU's array length is not a model parameter


def test_every_packaged_scene_splits_its_component_parameters():
    from tribocosim.cosim.scene.component_checks import component_of
    from tribocosim.cosim.scene.schema import is_sweep, parse_scene, read_document
    from tribocosim.paths import SCENES_DIR

    split = 0
    for path in sorted(SCENES_DIR.glob("*.toml")):
        if is_sweep(read_document(path)):
            continue
        scene, problems = parse_scene(path)
        assert scene is not None, problems
        for name, spec in scene.fmus.items():
            comp = component_of(spec)
            if comp is not None:
                comp.split(spec.parameters)
                split += 1
    assert split >= len(registry.components()), split
