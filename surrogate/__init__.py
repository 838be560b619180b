"""Offline mesoscale model (rough surfaces, Fourier-BEM contact, DEM flakes) and the friction table."""
