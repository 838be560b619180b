"""What the applications (:mod:`tribocosim.cosim.apps`) and the reports (:mod:`tribocosim.cosim.reports`) both use:
the strip-draw test with the pure model (:mod:`.stripdraw_experiment`), the monolithic references
(:mod:`.monolithic`) and the figures (:mod:`.plotting`). A layer below both, so that the reports never import an
application. Nothing here is imported by ``tribocosim run`` without ``--plot``."""
