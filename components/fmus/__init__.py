"""FMI 2.0 co-simulation adapters (pythonfmu) over the pure models, and their build.

- :mod:`components.fmus.StripDraw`: the strip-draw adapter (bundled into ``StripDraw.fmu``);
- :mod:`components.fmus.statecodec`: FMU-state bytes that carry numpy arrays (bundled);
- :mod:`components.fmus.exitguard`: work-around for pythonfmu 0.7.0's crash at exit (bundled);
- :mod:`components.fmus.build`: ``build_fmus(out_dir, names=None)``, a subprocess per FMU;
- :mod:`components.fmus.cli`: ``tribocosim fmu build [--out DIR]``.

This ``__init__`` imports nothing: it is bundled into every FMU, which needs only numpy.
"""
