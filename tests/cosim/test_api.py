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


def test_a_run_that_records_no_variable_has_its_times_and_no_columns(tmp_path):
    """One FMU, no connection and no output.variables: nothing is recorded. The result has the grid's times and no
    column (the C loop's buffer held one placeholder column, which made the columns fail to form), and asking for a
    variable names what is recorded and where that is set."""
    from tribocosim.cosim import run
    from tribocosim.cosim.scene.fmucache import component_fmu

    scene = tmp_path / "alone.toml"
    scene.write_text(f'[experiment]\nstop = 0.002\nstep = 1e-3\n[fmus.strip]\npath = "{component_fmu("stripdraw")}"\n'
                     'parameters = { normal_force = 12250.0, grip_velocity = 0.08 }\n')
    res = run(scene, write=False)
    assert list(res.time) == [0.0, 0.001, 0.002] and res.columns == {}
    with pytest.raises(KeyError, match="'strip.pull_force' is not recorded; the recorded columns: none"):
        res["strip.pull_force"]
