"""One module per ``studio`` verb; see :mod:`studio.cli` for the contract a verb module meets."""
