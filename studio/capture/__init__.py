"""studio.capture (see docs/interfaces.md)."""
