"""The FMUs of the components (C, FMI 2.0 and 3.0 co-simulation) and their build.

- :mod:`tribocosim.components.fmus.native_build`: ``build_native_fmus(out_dir, ...)``, the FMUs for every platform;
- :mod:`tribocosim.components.fmus.modeldescription`, :mod:`~tribocosim.components.fmus.modeldescription3`: what
  the model descriptions share, and the FMI 3.0 one;
- :mod:`tribocosim.components.fmus.fmu_cli`: ``tribocosim fmu build [--out DIR]`` (all three FMUs).

A component written in Python is a pythonfmu FMU of the user's own (docs/user-guide.md, "Your own component in
Python"); the project's physics has one FMI layer, the C one.
"""
