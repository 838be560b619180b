"""Scene and sweep documents (TOML) parsed once per file content: the document read back from the cache is the one
the parser gives, value for value and type for type; what JSON cannot hold, and what cannot be parsed, is not kept."""

from __future__ import annotations

import math
import tomllib

import pytest

from tribocosim.cosim.scene import documents
from tribocosim.cosim.scene.documents import TomlError, read_toml

TEXT = """
title = "a scene"
[experiment]
start = 0
stop = 2.06
step = 5e-4
big = 123456789012345678901
tiny = 5e-324
neg_zero = -0.0
plus_inf = inf
not_a_number = nan
flag = true
[fmus.strip]
parameters = { tool_length = 0.035, note = "ü → \\"quoted\\"", list = [1, 2.5, "x", [true, false]] }
[[connections]]
from = "a.y"
to = "b.u"
[[connections]]
from = "b.y"
to = "a.u"
"""


def _same(a, b) -> bool:
    """Equal values of the same types (NaN equal to NaN), keys in the same order."""
    if type(a) is not type(b):
        return False
    if isinstance(a, dict):
        return list(a) == list(b) and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, float):
        return (math.isnan(a) and math.isnan(b)) or (a == b and math.copysign(1, a) == math.copysign(1, b))
    return a == b


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """A cache folder of the test's own, and the number of times the parser ran."""
    monkeypatch.setenv("TRIBOCOSIM_CACHE", str(tmp_path / "cache"))
    parses = []
    parse = documents.parse_toml
    monkeypatch.setattr(documents, "parse_toml", lambda text: (parses.append(text), parse(text))[1])
    return parses


def test_a_content_is_parsed_once_and_read_back_as_the_parser_gives_it(tmp_path, cache):
    path = tmp_path / "scene.toml"
    path.write_text(TEXT, encoding="utf-8")
    first = read_toml(path)
    second = read_toml(path)
    assert len(cache) == 1, "the second read of the same content does not parse"
    assert _same(first, tomllib.loads(TEXT)) and _same(second, tomllib.loads(TEXT))
    assert isinstance(second["experiment"]["start"], int) and second["experiment"]["big"] == 123456789012345678901
    second["experiment"]["stop"] = 1.0  # a caller's change (overrides) reaches no other reader
    assert read_toml(path)["experiment"]["stop"] == 2.06
    other = tmp_path / "copy.toml"
    other.write_text(TEXT, encoding="utf-8")
    read_toml(other)
    assert len(cache) == 1, "another file of the same content is not parsed again"
    path.write_text(TEXT.replace("2.06", "1.5"), encoding="utf-8")
    assert read_toml(path)["experiment"]["stop"] == 1.5 and len(cache) == 2, "a changed content is parsed"


def test_a_document_with_a_date_is_parsed_every_time(tmp_path, cache):
    path = tmp_path / "dated.toml"
    path.write_text("when = 2024-05-09\n", encoding="utf-8")
    assert read_toml(path) == tomllib.loads("when = 2024-05-09\n")
    read_toml(path)
    assert len(cache) == 2, "JSON cannot hold a date: nothing kept"


def test_text_that_is_not_toml_raises_the_parsers_message_each_time(tmp_path, cache):
    path = tmp_path / "bad.toml"
    path.write_text("[experiment\nstop = 1\n", encoding="utf-8")
    for _ in range(2):
        with pytest.raises(TomlError, match=r"line 1"):
            read_toml(path)
    assert len(cache) == 2
    assert not list((tmp_path / "cache").rglob("*.json")), "nothing kept of a file that cannot be parsed"
