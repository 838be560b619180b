"""The digests remembered in the cache (components/native/toolchain/digests.py): computed again when a file changes,
and kept apart for two installations (two checkouts) that share one cache folder, so that neither takes the other's
digest for its own sources (an FMU built from one checkout's sources under the other's name)."""

from __future__ import annotations

import os

from tribocosim.components.native.toolchain import digests


def test_a_digest_is_computed_again_when_its_file_changes(tmp_path, monkeypatch):
    monkeypatch.setenv("TRIBOCOSIM_CACHE", str(tmp_path / "cache"))
    source = tmp_path / "a.c"
    source.write_text("one")
    calls = []
    compute = (lambda: calls.append(1) or source.read_text())
    assert digests.memo("fmu A 2", [source], compute) == "one"
    assert digests.memo("fmu A 2", [source], compute) == "one" and len(calls) == 1, "remembered, not computed"
    assert digests.remembered("fmu A 2") == "one"
    source.write_text("two!")
    os.utime(source, ns=(1, 1))
    assert digests.remembered("fmu A 2") is None
    assert digests.memo("fmu A 2", [source], compute) == "two!" and len(calls) == 2


def test_two_installations_sharing_a_cache_keep_their_own_digests(tmp_path, monkeypatch):
    monkeypatch.setenv("TRIBOCOSIM_CACHE", str(tmp_path / "cache"))
    mine, theirs = tmp_path / "mine.c", tmp_path / "theirs.c"
    mine.write_text("mine")
    theirs.write_text("theirs")
    monkeypatch.setattr(digests, "INSTALLATION", "/checkout/theirs")
    assert digests.memo("fmu Press 2", [theirs], theirs.read_text) == "theirs"
    monkeypatch.setattr(digests, "INSTALLATION", "/checkout/mine")
    assert digests.remembered("fmu Press 2") is None, "the other checkout's record is not this one's"
    assert digests.memo("fmu Press 2", [mine], mine.read_text) == "mine"
    monkeypatch.setattr(digests, "INSTALLATION", "/checkout/theirs")
    assert digests.remembered("fmu Press 2") == "theirs"
