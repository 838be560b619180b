"""The servo-hydraulic press: model, parameters and component description.

``PressParameters`` and ``PressModel`` are imported on first use.
"""

from tribocosim.lazy import lazy_exports

__getattr__, __all__ = lazy_exports(__name__, {"PressParameters": ".parameters", "PressModel": ".model"})
