"""studio.learning (see docs/interfaces.md)."""
