"""FMI 2.0 co-simulation adapters (pythonfmu) over the pure models, and their build.

- :mod:`tribocosim.components.fmus.adapter`: the FMI plumbing shared by the adapters (bundled into every FMU);
- :mod:`tribocosim.components.fmus.StripDraw`, :mod:`~tribocosim.components.fmus.Press`, :mod:`~tribocosim.components.fmus.DrawingMachine`:
  the adapters (each bundled into the FMU of its name);
- :mod:`tribocosim.components.fmus.statecodec`: FMU-state bytes that carry numpy arrays (bundled);
- :mod:`tribocosim.components.fmus.exitguard`: work-around for pythonfmu 0.7.0's crash at exit (bundled);
- :mod:`tribocosim.components.fmus.python_build`: ``build_fmus(out_dir, names=None)``, a subprocess per FMU;
- :mod:`tribocosim.components.fmus.fmu_cli`: ``tribocosim fmu build [--out DIR]`` (all three FMUs).

This ``__init__`` imports nothing: it is bundled into every FMU, which needs only numpy.
"""
