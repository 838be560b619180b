"""SSP 1.0 packages (System Structure and Parameterization): a scene written as one (:mod:`.export`), a package read
back as a scene for our master (:mod:`.reader`), and the names both use (:mod:`.names`).

:func:`fmpy_parameter_set` gathers a package's parameter bindings into the one set FMPy's ``simulate_ssp`` applies.
"""

from tribocosim.cosim.ssp.names import fmpy_parameter_set

__all__ = ["fmpy_parameter_set"]
