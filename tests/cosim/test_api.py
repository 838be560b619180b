"""tribocosim.run (cosim/api.py) checks what it is given before it runs, with the messages of the command line."""

from __future__ import annotations

import pytest

import tribocosim
from tribocosim.cosim.apps import run_cli
from tribocosim.errors import ParameterError


def test_overrides_must_be_a_dict():
    with pytest.raises(ParameterError) as err:
        tribocosim.run("demo", overrides="master.extrapolation=1")
    message = str(err.value)
    assert "overrides = 'master.extrapolation=1': a str" in message and "a dict of dotted scene keys" in message
    assert "--set KEY=VALUE" in message, message


def test_an_output_path_that_is_a_file_is_refused_before_the_run_with_the_clis_message(tmp_path, capsys):
    blocker = tmp_path / "results"
    blocker.write_text("not a folder")
    assert run_cli.main(["demo", "--out", str(blocker), "--quiet"]) == 2
    cli = capsys.readouterr().err.strip()
    with pytest.raises(ParameterError) as err:
        tribocosim.run("demo", blocker)
    assert cli == f"tribocosim run: {err.value}", (cli, str(err.value))
    with pytest.raises(ParameterError, match=f"cannot make the output folder {blocker / 'sub'}: {blocker} is a file"):
        tribocosim.run("demo", blocker / "sub")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results"] and blocker.read_text() == "not a folder"
