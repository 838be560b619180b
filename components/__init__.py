"""Runtime components of tribocosim: pure physics models and their thin FMI adapters.

Everything in this package imports numpy only (numba is optional and guarded), so that a
built FMU runs in an environment that has nothing but numpy.
"""
