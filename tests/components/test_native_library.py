"""The native core library behind the Python models (components/native/library.py): built from the FMUs' sources
into the cache, found there by a digest of what it is made of, and a clear error when it cannot be built."""

from __future__ import annotations

import pytest

from tribocosim.components.native import library, toolchain


def test_a_library_that_cannot_be_built_says_what_failed(tmp_path, monkeypatch):
    def no_compiler():
        raise toolchain.CompileError("the C compiler package 'ziglang' is not installed (pip install ziglang)")

    monkeypatch.setattr(toolchain, "zig_command", no_compiler)
    with pytest.raises(library.CoreBuildError, match="native core library cannot be built: the C compiler package "
                                                     "'ziglang' is not installed"):
        library.build(tmp_path / "libtc_core.so")
    assert not (tmp_path / "libtc_core.so").exists() and list(tmp_path.iterdir()) == [], "nothing left behind"


def test_the_cached_library_is_keyed_by_its_sources(tmp_path, monkeypatch):
    monkeypatch.setenv("TRIBOCOSIM_CACHE", str(tmp_path))
    path = library.library_path()
    assert path.parent == tmp_path / "core" and library.digest()[:20] in path.name and path.is_file()
    assert library.library_path() == path, "found, not built again"
