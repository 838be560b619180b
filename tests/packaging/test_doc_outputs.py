"""The documentation's figures that commands print are those commands' output now (cosim/apps/doc_outputs.py): a
stale figure is found and rewritten, a failing command is named, and on the shipped data every marked figure of the
README and docs/ is what its command prints (slow: it runs them all)."""

from __future__ import annotations

import sys

import pytest

from tribocosim.cosim.apps import doc_outputs


def _doc(tmp_path, body):
    path = tmp_path / "doc.md"
    path.write_text(body)
    return path


def test_a_stale_figure_is_found_named_and_rewritten(tmp_path, capsys):
    script = tmp_path / "says.py"
    script.write_text("import sys\nprint('mu_bar = 0.1286')\nprint('line two')\nprint('warning: x', file=sys.stderr)\n")
    path = _doc(tmp_path, f"mu_bar <!-- value: python {script} | ^mu_bar = (\\S+) -->0.1000<!-- /value --> here.\n\n"
                          f"<!-- output: python {script} | grep two -->\n```text\nold\n```\n<!-- output: end -->\n\n"
                          f"<!-- output: python {script} | stderr -->\n<!-- output: end -->\n")
    assert doc_outputs.main(["--check", str(path)]) == 1
    captured = capsys.readouterr()
    assert "a figure differs" in captured.out and "-old" in captured.err and "+line two" in captured.err
    assert doc_outputs.main(["--update", str(path)]) == 0
    text = path.read_text()
    assert "-->0.1286<!-- /value --> here." in text and "```text\nline two\n```\n" in text
    assert "```text\nwarning: x\n```\n" in text
    assert doc_outputs.main(["--check", str(path)]) == 0


def test_a_command_that_fails_or_a_pattern_that_matches_nothing_is_named(tmp_path, capsys):
    path = _doc(tmp_path, f"<!-- value: python -c \"import sys; sys.exit(3)\" | (x) -->?<!-- /value -->\n")
    assert doc_outputs.main(["--check", str(path)]) == 2
    assert "ended with status 3" in capsys.readouterr().err
    path = _doc(tmp_path, f"<!-- value: python -c print(1) | ^nothing (\\S+) -->?<!-- /value -->\n")
    assert doc_outputs.main(["--check", str(path)]) == 2
    assert "matches nothing" in capsys.readouterr().err


def test_an_included_file_is_shown_as_it_is(tmp_path):
    path = _doc(tmp_path, "<!-- include: docs/examples/strip_draw_model.py -->\n<!-- include: end -->\n")
    doc_outputs.main(["--update", str(path)])
    body = (doc_outputs.ROOT / "docs" / "examples" / "strip_draw_model.py").read_text()
    assert path.read_text() == f"<!-- include: docs/examples/strip_draw_model.py -->\n```python\n{body}```\n" \
                               "<!-- include: end -->\n"


@pytest.mark.slow
def test_every_figure_the_docs_state_as_a_commands_output_is_what_it_prints_now(capsys):
    code = doc_outputs.main(["--check"])
    out = capsys.readouterr()
    assert code == 0, out.out + out.err + f"\nrewrite them with: {sys.executable} -m tribocosim.cosim.apps.doc_outputs " \
                                          "--update"
