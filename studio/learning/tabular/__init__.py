"""Tabular Dyna-Q: the numba kernel with its four planners, and its policy files."""
