"""What the routers act on, one service per resource: the live source, the robot taught, the
capture, recordings (a folder store), demonstrations, training runs (the run queue and the
page's way to it), policies, watched rollouts and the watching of a policy, a recording's review
and its takes, and the downloads on a robot. Each list's owner announces its changes through :class:`ListChanges`."""

from __future__ import annotations

from ._capture import Capture as Capture
from ._changes import ListChanges as ListChanges
from ._demonstrations import Demonstrations as Demonstrations
from ._policies import Policies as Policies
from ._policies import PolicySource as PolicySource
from ._review import Reviewer as Reviewer
from ._robot_export import EXPORT_HEADER as EXPORT_HEADER
from ._robot_export import MEDIA_TYPES as MEDIA_TYPES
from ._robot_export import Download as Download
from ._robot_export import ExportFormat as ExportFormat
from ._robot_export import export_for_robot as export_for_robot
from ._robot_export import export_rollout as export_rollout
from ._robot_export import simulate_for_robot as simulate_for_robot
from ._robot_export import simulated_motion as simulated_motion
from ._robots import Robots as Robots
from ._rollouts import Rollouts as Rollouts
from ._runs import GROUP_SEPARATOR as GROUP_SEPARATOR
from ._runs import Run as Run
from ._runs import RunQueue as RunQueue
from ._sources import Sources as Sources
from ._store import RecordingStore as RecordingStore
from ._store import RecordingSummary as RecordingSummary
from ._store import StoredFile as StoredFile
from ._store import receive_upload as receive_upload
from ._store import recording_store as recording_store
from ._takes import TakeFlow as TakeFlow
from ._training import Training as Training
from ._watching import Watching as Watching
