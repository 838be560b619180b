"""The co-simulation engine: the master and what it is made of, independent of where a scene comes from.

:mod:`.master` (the time loop, rejection and rollback), :mod:`.algorithms` (Jacobi, Gauss-Seidel, iterative coupling),
:mod:`.stepcontrol` (fixed step, step doubling, energy residual), :mod:`.slave` (one FMU instance as the master sees
it, and its fmpy implementation), :mod:`.system` (slaves, links, coupling values), :mod:`.graph` (Gauss-Seidel order,
algebraic loops), :mod:`.timegrid` (integer time ticks), :mod:`.extrapolation` (input polynomials),
:mod:`.recorder` (observers: the recorded outputs, progress), :mod:`.native_loop` (the fixed-step loop in C,
``native/tc_master.c``) and :mod:`.libraries` (the FMUs' shared libraries, kept for the process). Nothing here reads a
scene file.
"""
