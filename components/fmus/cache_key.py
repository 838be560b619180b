"""The key under which the FMU cache remembers an FMU's source digest (:func:`tribocosim.components.native.toolchain.
digests.memo`): the FMU's name, its FMI version and the folder of the sources it is built from.

The folder is part of the key because the cache (``$TRIBOCOSIM_CACHE``) may be shared by several checkouts of the
project: a digest remembered for another checkout's files stays valid while those files are unchanged, and under a key
without the folder it would name that checkout's FMU. A light module, so that :mod:`tribocosim.cosim.scene.fmucache`
finds a remembered digest without importing the builder.
"""

from __future__ import annotations

from pathlib import Path

#: the components package folder, whose native sources, declarations and resources make the FMUs
SOURCES = Path(__file__).resolve().parents[1]


def digest_key(name: str, fmi_version: int = 2) -> str:
    """The cache key of the source digest of FMU ``name`` (model identifier) for FMI ``fmi_version``."""
    return f"fmu {name} {fmi_version} {SOURCES}"
