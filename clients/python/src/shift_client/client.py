"""Synchronous REST client of shiftd's HTTP API (DESIGN §5.3), over httpx."""

from __future__ import annotations

import re
import time
from urllib.parse import quote
from pathlib import Path
from typing import Any, Iterator, List, Optional, Union

import httpx

from .errors import ShiftError, error_for
from .events import PlanEvent, decode_messages, iter_sse
from .types import (
    OccupancyGrid,
    PlanAccepted,
    PlanDocument,
    PlanInfo,
    PlanRequest,
    RobotView,
    SiteSummary,
    SpeedProfile,
)

DEFAULT_URL = "http://127.0.0.1:7878"


def _seg(value: str) -> str:
    """One path segment, percent-encoded (a name with `/` cannot reach another route)."""
    return quote(value, safe="")


class PlanEvents:
    """An open ``GET /v1/plans/{id}/events`` stream: iterate it for typed events; close it (or use it as a
    context manager) to hang up. Iteration ends when the daemon ends the stream (after a ``done``, ``failed``
    or ``cancelled`` status, or on shutdown). Close it from the thread that iterates (break, then close): a
    thread blocked waiting for the next event is not woken by a close from elsewhere until an event or a
    keep-alive comes."""

    def __init__(self, response: httpx.Response) -> None:
        self._response = response
        self._events = decode_messages(iter_sse(response.iter_lines()))

    def __iter__(self) -> Iterator[PlanEvent]:
        return self

    def __next__(self) -> PlanEvent:
        try:
            return next(self._events)
        except StopIteration:
            self.close()
            raise

    def close(self) -> None:
        """Hangs up."""
        self._response.close()

    def __enter__(self) -> "PlanEvents":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class Client:
    """shiftd's HTTP API.

    ``base_url`` is the daemon's address (default ``http://127.0.0.1:7878``); ``token`` is sent as
    ``Authorization: Bearer …`` (the daemon asks for it on mutating routes when ``[http] auth_token`` is set);
    ``timeout`` is seconds per request (event streams wait for events without limit). Every method raises
    :class:`ShiftError` when the daemon answers with an error.

    >>> with Client("http://127.0.0.1:7878") as api:                            # doctest: +SKIP
    ...     plan = api.create_plan(PlanRequest("demo", (0.5, 0.5), RobotSpec(0.15, 0.3)))
    ...     info = api.wait_for_plan(plan.plan_id)
    ...     doc = api.get_path(plan.plan_id)
    """

    def __init__(
        self,
        base_url: str = DEFAULT_URL,
        token: Optional[str] = None,
        timeout: float = 30.0,
        transport: Optional[httpx.BaseTransport] = None,
    ) -> None:
        headers = {"Accept": "application/json"}
        if token:
            headers["Authorization"] = f"Bearer {token}"
        self._http = httpx.Client(base_url=base_url.rstrip("/"), headers=headers, timeout=timeout, transport=transport)

    def close(self) -> None:
        """Closes the connection pool."""
        self._http.close()

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _request(self, method: str, path: str, **kwargs: Any) -> Any:
        r = self._http.request(method, path, **kwargs)
        err = error_for(r.status_code, r.content, r.headers)
        if err is not None:
            raise err
        return r.json()

    # --- operations -------------------------------------------------------------------------------------------

    def healthy(self) -> bool:
        """``GET /healthz``: the daemon answers."""
        return self._http.get("/healthz").status_code == 200

    def ready(self) -> bool:
        """``GET /readyz``: store open and Zenoh session up."""
        return self._http.get("/readyz").status_code == 200

    def metrics_text(self) -> str:
        """``GET /metrics``: Prometheus exposition text."""
        r = self._http.get("/metrics", headers={"Accept": "text/plain"})
        err = error_for(r.status_code, r.content)
        if err is not None:
            raise err
        return r.text

    # --- sites ------------------------------------------------------------------------------------------------

    def upload_map(self, site: str, yaml: Union[str, bytes], image: bytes, image_name: str = "map.pgm") -> SiteSummary:
        """``POST /v1/sites/{site}/map``, multipart: a ROS map_server ``yaml`` and its ``image`` (PGM or PNG
        bytes). Replaces the site's map; returns its summary."""
        yaml_bytes = yaml.encode("utf-8") if isinstance(yaml, str) else yaml
        files = {
            "yaml": ("map.yaml", yaml_bytes, "application/yaml"),
            "image": (image_name, image, "application/octet-stream"),
        }
        return SiteSummary.from_json(self._request("POST", f"/v1/sites/{_seg(site)}/map", files=files))

    def upload_map_file(self, site: str, yaml_path: Union[str, Path]) -> SiteSummary:
        """Uploads the map_server YAML at ``yaml_path`` and the image its ``image:`` key names (relative to the
        YAML's folder)."""
        yaml_path = Path(yaml_path)
        text = yaml_path.read_text(encoding="utf-8")
        m = re.search(r"^\s*image\s*:\s*['\"]?([^'\"#\n]+?)['\"]?\s*(?:#.*)?$", text, re.MULTILINE)
        if m is None:
            raise ValueError(f"{yaml_path}: no `image:` key")
        image_path = Path(m.group(1))
        if not image_path.is_absolute():
            image_path = yaml_path.parent / image_path
        return self.upload_map(site, text, image_path.read_bytes(), image_name=image_path.name)

    def upload_grid(self, site: str, grid: OccupancyGrid) -> SiteSummary:
        """``POST /v1/sites/{site}/map`` with a JSON grid (nav_msgs/OccupancyGrid-like). Returns the summary."""
        return SiteSummary.from_json(self._request("POST", f"/v1/sites/{_seg(site)}/map", json=grid.to_json()))

    def get_site(self, site: str) -> SiteSummary:
        """``GET /v1/sites/{site}``: size, resolution, free cells, points in the live map."""
        return SiteSummary.from_json(self._request("GET", f"/v1/sites/{_seg(site)}"))

    # --- plans ------------------------------------------------------------------------------------------------

    def create_plan(self, request: PlanRequest, busy_wait_s: float = 0.0) -> PlanAccepted:
        """``POST /v1/plans``: the plan is queued (202); follow it with :meth:`wait_for_plan` or
        :meth:`plan_events`.

        A full queue answers 429 (``queue_full``) with ``Retry-After``. With ``busy_wait_s`` > 0 the request is
        sent again after the wait the daemon asks for (1 s when it names none) for up to that many seconds in
        all; the last 429 is raised when the time is up.
        """
        deadline = time.monotonic() + max(0.0, busy_wait_s)
        while True:
            try:
                return PlanAccepted.from_json(self._request("POST", "/v1/plans", json=request.to_json()))
            except ShiftError as e:
                wait = e.retry_after_s if e.retry_after_s is not None else 1.0
                if e.status != 429 or time.monotonic() + wait > deadline:
                    raise
                time.sleep(wait)

    def get_plan(self, plan_id: str) -> PlanInfo:
        """``GET /v1/plans/{id}``: status, progress 0-1, version, metrics once ready."""
        return PlanInfo.from_json(self._request("GET", f"/v1/plans/{_seg(plan_id)}"))

    def wait_for_plan(self, plan_id: str, timeout: float = 120.0, poll_s: float = 0.1) -> PlanInfo:
        """Polls the plan until its status is final (``ready``, ``active``, ``done``, ``failed`` or
        ``cancelled``) and returns it; check ``.status``. Raises ``TimeoutError`` after ``timeout`` seconds."""
        deadline = time.monotonic() + timeout
        delay = poll_s
        while True:
            info = self.get_plan(plan_id)
            if info.is_final:
                return info
            if time.monotonic() >= deadline:
                raise TimeoutError(f"plan {plan_id} still {info.status} after {timeout} s")
            time.sleep(min(delay, max(0.0, deadline - time.monotonic())))
            delay = min(delay * 1.5, 1.0)

    def get_path(self, plan_id: str) -> PlanDocument:
        """``GET /v1/plans/{id}/path``: the plan document, current version with every correction applied (409
        ``not_ready`` while it is computed)."""
        return PlanDocument.from_json(self._request("GET", f"/v1/plans/{_seg(plan_id)}/path"))

    def get_speed_profile(self, plan_id: str) -> SpeedProfile:
        """``GET /v1/plans/{id}/speed-profile``: per waypoint arc length (m), speed (m/s), time (s)."""
        return SpeedProfile.from_json(self._request("GET", f"/v1/plans/{_seg(plan_id)}/speed-profile"))

    def cancel_plan(self, plan_id: str) -> PlanInfo:
        """``DELETE /v1/plans/{id}``: cancels a queued or planning plan (409 once it finished)."""
        return PlanInfo.from_json(self._request("DELETE", f"/v1/plans/{_seg(plan_id)}"))

    def assign_plan(self, plan_id: str, robot: str) -> PlanInfo:
        """``POST /v1/plans/{id}/assign``: publishes the plan to ``robot`` over Zenoh and watches its path."""
        return PlanInfo.from_json(self._request("POST", f"/v1/plans/{_seg(plan_id)}/assign", json={"robot": robot}))

    def plan_events(self, plan_id: str) -> PlanEvents:
        """``GET /v1/plans/{id}/events``: an open stream of typed events (first the current status). Raises
        :class:`ShiftError` at once for an unknown plan."""
        timeout = httpx.Timeout(self._http.timeout.connect, read=None, write=self._http.timeout.write, pool=None)
        req = self._http.build_request(
            "GET", f"/v1/plans/{_seg(plan_id)}/events", headers={"Accept": "text/event-stream"}, timeout=timeout
        )
        r = self._http.send(req, stream=True)
        if not 200 <= r.status_code < 300:
            try:
                body = r.read()
            finally:
                r.close()
            raise ShiftError.from_response(r.status_code, body, r.headers)
        return PlanEvents(r)

    # --- robots -----------------------------------------------------------------------------------------------

    def list_robots(self) -> List[RobotView]:
        """``GET /v1/robots``: every robot seen, alive or lost."""
        return [RobotView.from_json(r) for r in self._request("GET", "/v1/robots")]

    def get_robot(self, robot: str) -> RobotView:
        """``GET /v1/robots/{id}``: pose, plan, progress, last correction, the site its data feeds."""
        return RobotView.from_json(self._request("GET", f"/v1/robots/{_seg(robot)}"))
