"""How a capture source is named (``studio record --source``, the page's source choice) and the
network source's default port.

A light module (no numpy, no device code): ``studio record --help`` and ``studio bridge --help``
read these at once, while the sources themselves load only when a capture starts.
"""

from __future__ import annotations

SOURCE_SPECS = (
    "simulator[:SEED] | FILE.tape.csv|.pose.csv|.hand.csv | udp[:[HOST:]PORT] | serial:PORT"
)
"""What :func:`source_from_spec` accepts (for help texts)."""
DEFAULT_PORT = 47110
"""UDP port of the network source unless told otherwise."""
