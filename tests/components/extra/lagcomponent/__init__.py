"""A small component outside the package (tests only): a first-order lag, y' = (k u - y) / tau."""
