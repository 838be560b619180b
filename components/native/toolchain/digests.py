"""Digests of files (and other facts computed from files), remembered in the cache by the files' stat signature, as
build tools remember what they built.

A digest over many files (an FMU's sources, its generators and its friction table) or of one large file (an FMU,
the table) costs milliseconds to tens of milliseconds each time it is computed; a run computes the same ones
again and again. :func:`memo` keeps each digest (or any value JSON can hold) in ``$TRIBOCOSIM_CACHE/digests/``
together with the signature of the files it was computed from, each file's (path, size, modification time in ns, inode): while every file still has
its signature the stored digest is returned, otherwise it is computed again and stored. An edit changes a file's
modification time (and usually its size), a replaced file its inode. The store is written atomically (a temporary
file renamed into place): concurrent processes never read half a record, and a lost race only recomputes. Each
installation of the package has records of its own (the record's name carries the package's folder): two checkouts
that share one cache folder never take each other's digests (:func:`remembered` trusts the files a record names).
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable, Iterable
from pathlib import Path

from tribocosim.components.native.toolchain.library import cache_dir


def signature(files: Iterable[Path]) -> list[list]:
    """``[[path, size, mtime_ns, inode], ...]`` of ``files`` (a missing file: ``[path, -1, -1, -1]``)."""
    out = []
    for f in files:
        try:
            st = os.stat(f)
            out.append([str(f), st.st_size, st.st_mtime_ns, st.st_ino])
        except OSError:
            out.append([str(f), -1, -1, -1])
    return out


#: the folder of this installation's components package: part of every record's name
INSTALLATION = str(Path(__file__).resolve().parents[2])


def _record(key: str) -> Path:
    name = hashlib.sha256(f"{INSTALLATION}\n{key}".encode()).hexdigest()[:32]
    return cache_dir() / "digests" / f"{name}.json"


def remembered(key: str) -> object:
    """The value :func:`memo` stored for ``key`` while every file it was computed from is unchanged, else None (for
    a caller that would have to do work to name the files)."""
    try:
        stored = json.loads(_record(key).read_text(encoding="utf-8"))
        files = [f[0] for f in stored["files"]]
        if stored.get("key") == key and stored["files"] == signature(files):
            return stored["digest"]
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        pass
    return None


def memo(key: str, files: Iterable[Path], compute: Callable[[], object]) -> object:
    """The value ``compute()`` returns for ``key`` (a digest, or any value JSON holds as it is), computed again only
    when one of ``files`` changed. An exception of ``compute`` is raised, and nothing is remembered."""
    files = list(files)
    sig = signature(files)
    record = _record(key)
    try:
        stored = json.loads(record.read_text(encoding="utf-8"))
        if stored.get("key") == key and stored.get("files") == sig:
            return stored["digest"]
    except (OSError, ValueError, KeyError, AttributeError):
        pass
    digest = compute()
    if signature(files) != sig:  # a file changed while it was read: do not store what may mix two versions
        return digest
    from tribocosim.atomic import write_text

    try:
        record.parent.mkdir(parents=True, exist_ok=True)
        write_text(record, json.dumps({"key": key, "files": sig, "digest": digest}))
    except OSError:  # a cache that cannot be written costs time, not results
        pass
    return digest


def file_sha256(path: Path) -> str:
    """SHA-256 of a file's content (remembered by its signature)."""
    path = Path(path).resolve()

    def compute() -> str:
        h = hashlib.sha256()
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
        return h.hexdigest()

    return memo(f"sha256 {path}", [path], compute)
