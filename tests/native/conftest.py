"""Fixtures of the native (C) tests: a build of chosen C sources with undefined behaviour trapping and an
allocation-counting shim, so that tests can check that nothing leaks on any path. The models themselves are
tested through their bindings (the package's core library, :mod:`tribocosim.components.native.toolchain.library`).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tribocosim.components.native.toolchain.compiler import compile_shared, source

TC_OK, TC_DISCARD, TC_ERROR, TC_NOMEM = 0, 1, 2, 3


@pytest.fixture(scope="session")
def native_headers(tmp_path_factory) -> Path:
    """A folder with the parameter headers generated from the component descriptions (as the FMU build does)."""
    from tribocosim.components import registry
    from tribocosim.components.native.toolchain.declarations import write_params_headers

    folder = tmp_path_factory.mktemp("native_headers")
    write_params_headers(folder, registry.components().values())
    return folder


# Test-only allocator shim of the checked builds: live allocations are counted and the n-th allocation can be
# made to fail (tc_count_live, tc_count_fail_after), so that the tests can check that nothing leaks on any path.
_COUNT_H = r"""
#include <stdlib.h>
#include "tc_common.h"
TC_API void *tc_count_malloc(size_t n);
TC_API void *tc_count_calloc(size_t a, size_t b);
TC_API void *tc_count_realloc(void *p, size_t n);
TC_API void tc_count_free(void *p);
#define malloc(n) tc_count_malloc(n)
#define calloc(a, b) tc_count_calloc(a, b)
#define realloc(p, n) tc_count_realloc(p, n)
#define free(p) tc_count_free(p)
"""
_COUNT_C = r"""
#undef malloc
#undef calloc
#undef realloc
#undef free
static long live = 0, countdown = -1;
static int granted(void) {
    if (countdown == 0) return 0;
    if (countdown > 0) --countdown;
    return 1;
}
TC_API void *tc_count_malloc(size_t n) { void *p = granted() ? malloc(n) : NULL; if (p) ++live; return p; }
TC_API void *tc_count_calloc(size_t a, size_t b) { void *p = granted() ? calloc(a, b) : NULL; if (p) ++live; return p; }
TC_API void *tc_count_realloc(void *p, size_t n) {
    void *q = granted() ? realloc(p, n) : NULL;
    if (q && !p) ++live;
    return q;
}
TC_API void tc_count_free(void *p) { if (p) { --live; free(p); } }
TC_API long tc_count_live(void) { return live; }
TC_API void tc_count_fail_after(long n) { countdown = n; }
"""


@pytest.fixture(scope="session")
def native_checked_compile():
    """``build(sources, folder, name, defines=()) -> Path``: C sources (names in the native folder) compiled for
    linux64 with undefined behaviour trapping and the allocation-counting shim (test builds only)."""

    def build(sources, folder: Path, name: str, defines=(), include_dirs=()) -> Path:
        (folder / "tc_count.h").write_text(_COUNT_H)
        (folder / "tc_count.c").write_text(_COUNT_C)
        return compile_shared([*map(source, sources), folder / "tc_count.c"], folder / name, "linux64",
                              defines=["TC_EXPORT_CORE", *defines], include_dirs=include_dirs,
                              extra_flags=["-include", str(folder / "tc_count.h"), "-fsanitize=undefined",
                                           "-fsanitize-trap=undefined"])

    return build
