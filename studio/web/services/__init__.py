"""What the routers act on, one service per resource: the folder stores (recordings,
demonstrations, policies), the run queue, and the downloads on a robot."""

from __future__ import annotations

from ._robot_export import MEDIA_TYPES as MEDIA_TYPES
from ._robot_export import ExportFormat as ExportFormat
from ._robot_export import export_for_robot as export_for_robot
from ._robot_export import export_rollout as export_rollout
from ._robot_export import simulate_for_robot as simulate_for_robot
from ._runs import GROUP_SEPARATOR as GROUP_SEPARATOR
from ._runs import Run as Run
from ._runs import RunQueue as RunQueue
from ._runs import prepare_run as prepare_run
from ._store import RecordingSummary as RecordingSummary
from ._store import StoredFile as StoredFile
from ._store import demonstration_store as demonstration_store
from ._store import policy_store as policy_store
from ._store import receive_upload as receive_upload
from ._store import recording_store as recording_store
