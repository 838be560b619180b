"""The strip-draw model: 1D bar under a pad, interface law, debris transport, friction law.

Pure physics (numpy; numba optional): no FMI, no printing. The table module is the one place
that reads and writes friction-table files.
"""

from components.stripdraw.friction import closed_form_table, make_friction_law
from components.stripdraw.model import INPUT_NAMES, OUTPUT_NAMES, StripDrawModel
from components.stripdraw.parameters import StripDrawParameters
from components.stripdraw.table import FrictionTable, read_table, write_table

__all__ = [
    "INPUT_NAMES",
    "OUTPUT_NAMES",
    "FrictionTable",
    "StripDrawModel",
    "StripDrawParameters",
    "closed_form_table",
    "make_friction_law",
    "read_table",
    "write_table",
]
