"""Zenoh key expressions of DESIGN §5.4, built exactly as ``proto/src/keys.rs`` (``KeySpace``) builds them:
``{prefix}/{fleet}/robots/{robot}/{odom|cloud|scan|plan|plan_path|corrections|alive}`` and
``{prefix}/{fleet}/plans/{plan}/status``; names are validated by the same rules."""

from __future__ import annotations

from dataclasses import dataclass

MAX_NAME_BYTES = 64
"""Longest accepted name, characters (names are ASCII)."""

_ALLOWED = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_")


class InvalidName(ValueError):
    """A robot name, fleet, prefix or plan id that cannot be part of a key expression."""

    def __init__(self, what: str, value: str, reason: str) -> None:
        super().__init__(f"invalid {what} `{value}`: {reason}")
        self.what = what
        self.value = value
        self.reason = reason




def validate_name(what: str, value: str) -> None:
    """The one name rule (``proto/src/keys.rs`` ``validate_name``): 1-64 characters of ``[A-Za-z0-9_-]``, for
    sites, robots, plan ids, the fleet and each prefix chunk."""
    if not value:
        raise InvalidName(what, value, "must not be empty")
    if len(value) > MAX_NAME_BYTES:
        raise InvalidName(what, value, "is longer than 64 characters")
    if any(c not in _ALLOWED for c in value):
        raise InvalidName(what, value, "may hold only letters, digits, '-' and '_'")


def validate_path(what: str, value: str) -> None:
    """Checks a multi-chunk prefix such as ``shift`` or ``acme/site1``: chunks separated by single ``/``."""
    if not value:
        raise InvalidName(what, value, "must not be empty")
    for chunk in value.split("/"):
        try:
            validate_name(what, chunk)
        except InvalidName as e:
            raise InvalidName(what, value, e.reason) from None


@dataclass(frozen=True)
class KeySpace:
    """The key space of one fleet: every key is ``{prefix}/{fleet}/…``. Defaults: prefix ``shift``, fleet
    ``default`` (the daemon's ``[zenoh] prefix`` and ``fleet``)."""

    prefix: str = "shift"
    fleet: str = "default"

    def __post_init__(self) -> None:
        validate_path("prefix", self.prefix)
        validate_name("fleet", self.fleet)

    def _robot_key(self, robot: str, leaf: str) -> str:
        validate_name("robot name", robot)
        return f"{self.prefix}/{self.fleet}/robots/{robot}/{leaf}"

    def odom(self, robot: str) -> str:
        """Robot → server odometry (nav_msgs/Odometry CDR or JSON ``{x, y, yaw, vx, vy, wz, stamp}``)."""
        return self._robot_key(robot, "odom")

    def cloud(self, robot: str) -> str:
        """Robot → server sensor_msgs/PointCloud2 CDR."""
        return self._robot_key(robot, "cloud")

    def scan(self, robot: str) -> str:
        """Robot → server sensor_msgs/LaserScan CDR."""
        return self._robot_key(robot, "scan")

    def plan(self, robot: str) -> str:
        """Server → robot plan JSON (DESIGN §5.1); also the queryable that answers the current version."""
        return self._robot_key(robot, "plan")

    def plan_path(self, robot: str) -> str:
        """Server → robot nav_msgs/Path CDR of the plan, map frame."""
        return self._robot_key(robot, "plan_path")

    def corrections(self, robot: str) -> str:
        """Server → robot correction JSON."""
        return self._robot_key(robot, "corrections")

    def alive(self, robot: str) -> str:
        """The robot's liveliness token."""
        return self._robot_key(robot, "alive")

    def plan_status(self, plan_id: str) -> str:
        """Server → anyone plan status JSON (also a queryable)."""
        validate_name("plan id", plan_id)
        return f"{self.prefix}/{self.fleet}/plans/{plan_id}/status"
