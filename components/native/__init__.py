"""The native (C) implementation of the runtime models, and the toolchain that compiles it.

The C sources in this folder (package data) follow the Python models of
:mod:`tribocosim.components` equation by equation; the Python models stay the readable reference
and the tests hold the two together. :mod:`.toolchain` compiles them with the C compiler that the
``ziglang`` package installs (no system compiler needed), for linux64, win64 and darwin64.
"""
