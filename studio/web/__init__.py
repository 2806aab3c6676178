"""studio.web (see docs/interfaces.md)."""
