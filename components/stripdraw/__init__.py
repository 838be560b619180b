"""The strip-draw model: 1D bar under a pad, interface law, debris transport, friction law.

A binding over the native core (``components/native``): no FMI, no printing. The table module is the one
place that reads and writes friction-table files.

The names below are imported on first use, so that importing a light module of this package
(``parameters``, ``table``) does not load the native library.
"""

from tribocosim.lazy import lazy_exports

__getattr__, __all__ = lazy_exports(__name__, {
    "INPUT_NAMES": ".model",
    "OUTPUT_NAMES": ".model",
    "StripDrawModel": ".model",
    "StripDrawParameters": ".parameters",
    "FrictionTable": ".table",
    "read_table": ".table",
    "write_table": ".table",
    "closed_form_table": ".friction",
    "make_friction_law": ".friction",
})
