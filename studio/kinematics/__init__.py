"""studio.kinematics (see docs/interfaces.md)."""

from ._errors import KinematicsError as KinematicsError
from ._puma import PUMA_QN as PUMA_QN
from ._puma import PUMA_QR as PUMA_QR
from ._puma import PUMA_QS as PUMA_QS
from ._puma import PUMA_QZ as PUMA_QZ
from ._puma import IKConfig as IKConfig
from ._puma import IKResult as IKResult
from ._puma import LinkVisual as LinkVisual
from ._puma import Puma560 as Puma560
