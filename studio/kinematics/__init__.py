"""studio.kinematics (see docs/interfaces.md)."""
