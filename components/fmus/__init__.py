"""FMI 2.0 co-simulation adapters (pythonfmu) over the pure models, and their build.

- :mod:`components.fmus.adapter`: the FMI plumbing shared by the adapters (bundled into every FMU);
- :mod:`components.fmus.StripDraw`, :mod:`~components.fmus.Press`, :mod:`~components.fmus.DrawingMachine`:
  the adapters (each bundled into the FMU of its name);
- :mod:`components.fmus.statecodec`: FMU-state bytes that carry numpy arrays (bundled);
- :mod:`components.fmus.exitguard`: work-around for pythonfmu 0.7.0's crash at exit (bundled);
- :mod:`components.fmus.build`: ``build_fmus(out_dir, names=None)``, a subprocess per FMU;
- :mod:`components.fmus.cli`: ``tribocosim fmu build [--out DIR]`` (all three FMUs).

This ``__init__`` imports nothing: it is bundled into every FMU, which needs only numpy.
"""
