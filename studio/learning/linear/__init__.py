"""Linear Dyna-Q over tile-coded features: the kernel, its environments, the factored and common
action values, and tile-coded policy files."""
