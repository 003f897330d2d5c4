"""The one exception of the REST client: an answer of the API that is not a success."""

from __future__ import annotations

import json
from email.utils import parsedate_to_datetime
from datetime import datetime, timezone
from typing import Mapping, Optional, Tuple, Type


def parse_retry_after(value: Optional[str], now: Optional[datetime] = None) -> Optional[float]:
    """Seconds a ``Retry-After`` header asks to wait: delta-seconds or an HTTP date (RFC 9110 §10.2.3);
    ``None`` when absent or unreadable, never negative."""
    if value is None:
        return None
    text = value.strip()
    if text.isdigit():
        return float(text)
    try:
        when = parsedate_to_datetime(text)
    except (TypeError, ValueError, IndexError):
        return None
    if when.tzinfo is None:
        when = when.replace(tzinfo=timezone.utc)
    return max(0.0, (when - (now or datetime.now(timezone.utc))).total_seconds())


class ShiftError(Exception):
    """A non-2xx answer of shiftd: its HTTP ``status`` and the API's ``{"error": {"code", "message"}}``.

    ``code`` is the API's stable machine-readable code (``invalid_request``, ``not_found``, ``not_ready``,
    ``invalid_state``, ``queue_full``, ``unauthorized``, ``forbidden``, …). An answer without that body (a proxy
    in between, a daemon too old) gets ``code`` ``http_<status>`` and its text as ``message``. Network failures
    are not answers: they raise ``httpx.TransportError``. ``retry_after_s`` is the wait a 429 or 503 asks for
    (its ``Retry-After`` header), ``None`` when it names none.
    """

    def __init__(self, status: int, code: str, message: str, retry_after_s: Optional[float] = None) -> None:
        super().__init__(f"HTTP {status} {code}: {message}")
        self.status = status
        self.code = code
        self.message = message
        self.retry_after_s = retry_after_s

    @classmethod
    def from_response(cls, status: int, body: bytes, headers: Optional[Mapping[str, str]] = None) -> "ShiftError":
        """The error of an answer with ``status``, ``body`` and ``headers``."""
        text = body.decode("utf-8", errors="replace")
        retry = None
        if headers is not None:
            # httpx's headers ignore case; a plain mapping may carry either spelling.
            retry = parse_retry_after(headers.get("retry-after") or headers.get("Retry-After"))
        try:
            detail = json.loads(text)["error"]
            return cls(status, str(detail["code"]), str(detail["message"]), retry)
        except (ValueError, KeyError, TypeError):
            return cls(status, f"http_{status}", text.strip()[:2000], retry)

    def __reduce__(self) -> Tuple[Type["ShiftError"], Tuple[int, str, str, Optional[float]]]:
        """Keeps the fields through pickling (multiprocessing, pytest-xdist)."""
        return (type(self), (self.status, self.code, self.message, self.retry_after_s))


def error_for(status: int, body: bytes, headers: Optional[Mapping[str, str]] = None) -> Optional[ShiftError]:
    """``None`` for a 2xx status, else the error it carries."""
    return None if 200 <= status < 300 else ShiftError.from_response(status, body, headers)
