"""The build of the native code: :mod:`.compiler` (zig's C compiler for every platform), :mod:`.declarations` (the C
parameter structs and FMU variable tables generated from the component descriptions) and :mod:`.library` (the core
library of the models, built on first use and loaded with ctypes by the Python bindings)."""
