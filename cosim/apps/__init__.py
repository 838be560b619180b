"""Applications of the engine: the command lines (``tribocosim run``, ``ssp``, ``report``, ``demo``, ``calibrate``),
scene sweeps, the strip-draw experiment with the pure models, the monolithic references and the plots. The reports
themselves are :mod:`tribocosim.cosim.reports`."""
