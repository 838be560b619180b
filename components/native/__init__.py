"""The native (C) implementation of the runtime models, in one folder per role.

``core/``
    the models' physics: the strip draw (bar, interface law, debris transport), its friction law and the friction
    table in memory with its lookup, the press and the drawing machine; no FMI code, no file formats, no printing.
``fmi/``
    the FMI 2.0 and 3.0 layers over one version-independent instance core, and each component's glue
    (``tc_<name>_fmu.c``: the component functions of ``tc_fmu.h``).
``resource_io/``
    the files the C code reads and writes (the array file of the friction table's resource form, the nodal-field
    CSV file) and their Python writers and readers.
``toolchain/``
    the Python side of the build: the C compiler of the ``ziglang`` package, the C declarations generated from the
    component descriptions, and the core library the Python bindings load.

The C folders are package data; every compile has all of them on its include path. A core file includes only core
headers, a resource_io file only core and resource_io headers (``tests/native/test_native_sources.py``).
"""
