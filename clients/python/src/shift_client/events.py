"""Plan events of ``GET /v1/plans/{id}/events`` (Server-Sent Events, ``PlanEvent`` in ``proto/src/api.rs``), the
mission views of ``GET /v1/missions/{id}/events`` (``mission`` events, ``MissionView`` in
``proto/src/mission.rs``), and the SSE line parser that reads them.

Every event's data is JSON tagged by ``type``: ``status``, ``progress``, ``region-ready``, ``correction``. The
first event of a stream is the plan's current status; the daemon ends the stream after a ``done``, ``failed`` or
``cancelled`` status (a ``ready`` plan's stream stays open: corrections follow once it is assigned).

A mission's stream carries its whole view as each ``mission`` event: first the current one, then one on every
change (about once a second at most while only progress and measured coverage move); it ends after ``done``,
``failed`` or ``cancelled``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any, Dict, Iterable, Iterator, List, Mapping, Optional, Union

from .types import Correction, MissionView, PlanInfo, Point2, _points


@dataclass(frozen=True)
class StatusEvent:
    """The plan's status changed (also the first event of every stream)."""

    plan: PlanInfo


@dataclass(frozen=True)
class ProgressEvent:
    """Computation advanced: ``progress`` 0-1."""

    plan_id: str
    progress: float


@dataclass(frozen=True)
class RegionReadyEvent:
    """A region's cover path is computed (before it is linked into the tour): contour and path, m, map frame."""

    plan_id: str
    region: int
    polygon: List[Point2]
    path: List[Point2]


@dataclass(frozen=True)
class CorrectionEvent:
    """A correction replaced a stretch of the plan (the robot got it on its corrections key)."""

    correction: Correction


@dataclass(frozen=True)
class UnknownEvent:
    """An event type this client does not know (a newer daemon): its SSE name and JSON data."""

    name: str
    data: Any


PlanEvent = Union[StatusEvent, ProgressEvent, RegionReadyEvent, CorrectionEvent, UnknownEvent]


def parse_event(name: str, data: Mapping[str, Any]) -> PlanEvent:
    """The typed event of one SSE message (``name`` is its ``event:`` field, ``data`` its parsed JSON)."""
    kind = data.get("type", name) if isinstance(data, Mapping) else name
    if kind == "status":
        return StatusEvent(PlanInfo.from_json(data))
    if kind == "progress":
        return ProgressEvent(str(data["plan_id"]), float(data["progress"]))
    if kind == "region-ready":
        r = data["region"]
        return RegionReadyEvent(str(data["plan_id"]), int(r["region"]), _points(r.get("polygon")), _points(r.get("path")))
    if kind == "correction":
        return CorrectionEvent(Correction.from_json(data))
    return UnknownEvent(name, data)


@dataclass(frozen=True)
class SseMessage:
    """One Server-Sent Events message: ``event`` name (``message`` when absent), ``data`` lines joined by
    newlines, ``id`` when given."""

    event: str
    data: str
    id: Optional[str] = None


def iter_sse(lines: Iterable[str]) -> Iterator[SseMessage]:
    """SSE messages of a stream of text lines (without line ends), per the HTML living standard: ``field:
    value`` lines, one optional space after the colon, comment lines starting with ``:`` (keep-alives) ignored,
    a blank line dispatches; a message without data is not dispatched."""
    event: Optional[str] = None
    data: List[str] = []
    last_id: Optional[str] = None
    for line in lines:
        if line == "":
            if data:
                yield SseMessage(event or "message", "\n".join(data), last_id)
            event, data = None, []
            continue
        if line.startswith(":"):
            continue
        name, sep, value = line.partition(":")
        if sep and value.startswith(" "):
            value = value[1:]
        if name == "event":
            event = value
        elif name == "data":
            data.append(value)
        elif name == "id" and "\0" not in value:
            last_id = value
        # `retry` and unknown fields are ignored.
    # A stream that ends without a final blank line drops the incomplete message (as browsers do).


def decode_messages(messages: Iterable[SseMessage]) -> Iterator[PlanEvent]:
    """Typed plan events of SSE messages (data parsed as JSON)."""
    for m in messages:
        data: Dict[str, Any] = json.loads(m.data)
        yield parse_event(m.event, data)


def decode_mission_messages(messages: Iterable[SseMessage]) -> Iterator[MissionView]:
    """Mission views of SSE messages: the data of each ``mission`` event; events of other names (a newer
    daemon's) are skipped."""
    for m in messages:
        if m.event == "mission":
            yield MissionView.from_json(json.loads(m.data))
