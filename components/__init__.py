"""Runtime components of tribocosim: the strip draw, the press and the drawing machine.

A component is declared once (``<name>/component.py``: variables, units, ranges, resources; found by
:mod:`.registry`), and its model is a thin Python binding (``<name>/model.py``, :mod:`.linear_model`) over the one
C core in :mod:`.native`, which the FMUs run too; :mod:`.fmus` builds the FMUs (C, FMI 2.0 and 3.0). Nothing here imports the co-simulation or the mesoscale code.
"""
