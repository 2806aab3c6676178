"""studio.kinematics (see docs/interfaces.md)."""

from ._errors import KinematicsError as KinematicsError
