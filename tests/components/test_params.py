"""A parameter class made by ``components.params.parameters`` behaves as ``dataclasses.dataclass(frozen=True)`` makes
it: the twin classes below, one of each, construct, print, compare, hash, refuse assignment, replace and convert alike,
and the shipped parameter classes are dataclasses whose fields and validation are unchanged."""

from __future__ import annotations

import dataclasses
import pickle

import pytest

from tribocosim.errors import ParameterError
from tribocosim.components.params import param, parameters, validate_fields


def _twin(decorate):
    class Twin:
        length: float = param(0.035, "m", "a length", 1e-4, 1.0)
        count: int = param(3, "1", "a count", 1, 10, integer=True)
        mode: str = param("a", "", "a choice", choices=("a", "b"))
        seen = ()  # not a field: no annotation

        def __post_init__(self) -> None:
            validate_fields(self)

        def doubled(self) -> float:
            return 2 * self.length

    return decorate(Twin)


OURS = _twin(parameters)
THEIRS = _twin(dataclasses.dataclass(frozen=True))


@pytest.mark.parametrize("args, kwargs", [((), {}), ((0.07,), {}), ((0.07, 4), {"mode": "b"}), ((), {"count": 2.0})])
def test_construction_printing_equality_and_hash_are_the_dataclasses(args, kwargs):
    ours, theirs = OURS(*args, **kwargs), THEIRS(*args, **kwargs)
    assert repr(ours) == repr(theirs)
    assert dataclasses.asdict(ours) == dataclasses.asdict(theirs)
    assert type(ours.count) is int, "validate_fields normalises the integer field in __post_init__"
    assert ours == OURS(*args, **kwargs) and ours != OURS(0.5) and ours != theirs
    assert hash(ours) == hash(OURS(*args, **kwargs)) == hash(theirs)
    assert ours.doubled() == theirs.doubled()
    assert [f.name for f in dataclasses.fields(ours)] == [f.name for f in dataclasses.fields(theirs)]
    assert dataclasses.is_dataclass(ours) and ours.__match_args__ == theirs.__match_args__


def test_bad_arguments_are_refused_as_the_dataclass_refuses_them():
    for cls in (OURS, THEIRS):
        with pytest.raises(TypeError, match="unexpected keyword argument 'size'"):
            cls(size=1.0)
        with pytest.raises(TypeError, match="multiple values for argument 'length'"):
            cls(0.1, length=0.2)
        with pytest.raises(TypeError, match="positional arguments"):
            cls(0.1, 2, "a", 5)
        with pytest.raises(ParameterError, match="length = 2.0 m is out of range"):
            cls(2.0)


def test_a_field_without_a_default_is_required_and_a_default_factory_is_called_per_instance():
    @parameters
    class Free:
        name: str
        tags: list = dataclasses.field(default_factory=list)

    with pytest.raises(TypeError, match="missing 1 required argument: 'name'"):
        Free()
    a, b = Free("a"), Free("b")
    assert a.tags == [] and a.tags is not b.tags and repr(a).endswith("Free(name='a', tags=[])")


def test_instances_are_frozen_and_replace_revalidates():
    p = OURS(0.07)
    with pytest.raises(dataclasses.FrozenInstanceError, match="cannot assign to field 'length'"):
        p.length = 0.1
    with pytest.raises(dataclasses.FrozenInstanceError, match="cannot delete field 'length'"):
        del p.length
    q = dataclasses.replace(p, count=5)
    assert (q.length, q.count, p.count) == (0.07, 5, 3)
    with pytest.raises(ParameterError, match="count = 11"):
        dataclasses.replace(p, count=11)


def test_the_shipped_parameter_classes_are_frozen_dataclasses_of_their_fields():
    from tribocosim.components.machine.parameters import MachineParameters
    from tribocosim.components.press.parameters import PressParameters
    from tribocosim.components.stripdraw.component import StripDrawFiles
    from tribocosim.components.stripdraw.parameters import StripDrawParameters

    for cls in (MachineParameters, PressParameters, StripDrawFiles, StripDrawParameters):
        default = cls()
        names = [f.name for f in dataclasses.fields(cls)]
        fields = ", ".join(f"{n}={getattr(default, n)!r}" for n in names)
        assert names and repr(default) == f"{cls.__qualname__}({fields})"
        assert default == cls() and hash(default) == hash(cls()) and pickle.loads(pickle.dumps(default)) == default
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(default, names[0], getattr(default, names[0]))
    with pytest.raises(ParameterError, match="tool_length"):
        StripDrawParameters(tool_length=-1.0)
