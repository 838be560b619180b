"""Runtime components of tribocosim: the strip draw, the press and the drawing machine.

A component is declared once (``<name>/component.py``: variables, units, ranges, resources; found by
:mod:`.registry`), and its model is a thin Python binding (``<name>/model.py``, :mod:`.linear_model`) over the one
C core in :mod:`.native`, which the FMUs run too; :mod:`.fmus` builds the FMUs (native C, or pythonfmu for a
component written in Python). Nothing here imports the co-simulation or the mesoscale code.
"""
