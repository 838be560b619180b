"""Shipped data (package data of ``tribocosim.models``): ``friction_table.npz`` and ``scenes/*.toml``.

Found as this package's folder by :mod:`tribocosim.paths`, so it works from a wheel and from an editable install
alike.
"""
