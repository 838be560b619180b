"""The drawing machine: model, parameters and component description.

``MachineParameters`` and ``MachineModel`` are imported on first use.
"""

from tribocosim.lazy import lazy_exports

__getattr__, __all__ = lazy_exports(__name__, {"MachineParameters": ".parameters", "MachineModel": ".model"})
