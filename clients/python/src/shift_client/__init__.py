"""shift-client: Python client of SHIFT's coverage-planning daemon ``shiftd``.

- :class:`Client`: the HTTP/JSON API (DESIGN §5.3), synchronous, over httpx; errors raise :class:`ShiftError`.
- :class:`Robot`: a robot's side over Zenoh (DESIGN §5.4): liveliness token, odometry and clouds out, plan and
  corrections in, corrections applied by version with a plan query on a gap.
- The wire documents as dataclasses (:mod:`shift_client.types`), plan and mission events
  (:mod:`shift_client.events`) and the key expressions (:class:`KeySpace`).
"""

from .client import DEFAULT_URL, Client, MissionEvents, PlanEvents
from .errors import ShiftError
from .events import (
    CorrectionEvent,
    PlanEvent,
    ProgressEvent,
    RegionReadyEvent,
    StatusEvent,
    UnknownEvent,
)
from .keys import InvalidName, KeySpace
from .robot import DEFAULT_ENDPOINT, Robot, peer_config
from .types import (
    FINAL_STATUSES,
    MISSION_SETTLED_STATUSES,
    AttributeBlob,
    Correction,
    CorrectionError,
    MissionAccepted,
    MissionCoverage,
    MissionPlanView,
    MissionRequest,
    MissionRobot,
    MissionView,
    OccupancyGrid,
    PlanAccepted,
    PlanDocument,
    PlanInfo,
    PlanMetrics,
    PlanOptions,
    PlanRequest,
    Region,
    RobotSpec,
    RobotView,
    SiteSummary,
    SpeedProfile,
    SpeedSample,
    VersionGap,
    Waypoint,
)

__all__ = [
    "DEFAULT_ENDPOINT",
    "DEFAULT_URL",
    "FINAL_STATUSES",
    "MISSION_SETTLED_STATUSES",
    "AttributeBlob",
    "Client",
    "Correction",
    "CorrectionError",
    "CorrectionEvent",
    "InvalidName",
    "KeySpace",
    "MissionAccepted",
    "MissionCoverage",
    "MissionEvents",
    "MissionPlanView",
    "MissionRequest",
    "MissionRobot",
    "MissionView",
    "OccupancyGrid",
    "PlanAccepted",
    "PlanDocument",
    "PlanEvent",
    "PlanEvents",
    "PlanInfo",
    "PlanMetrics",
    "PlanOptions",
    "PlanRequest",
    "ProgressEvent",
    "Region",
    "RegionReadyEvent",
    "Robot",
    "RobotSpec",
    "RobotView",
    "ShiftError",
    "SiteSummary",
    "SpeedProfile",
    "SpeedSample",
    "StatusEvent",
    "UnknownEvent",
    "VersionGap",
    "Waypoint",
    "peer_config",
]
