"""The one exception of the REST client: an answer of the API that is not a success."""

from __future__ import annotations

import json
from typing import Optional, Tuple, Type


class ShiftError(Exception):
    """A non-2xx answer of shiftd: its HTTP ``status`` and the API's ``{"error": {"code", "message"}}``.

    ``code`` is the API's stable machine-readable code (``invalid_request``, ``not_found``, ``not_ready``,
    ``invalid_state``, ``queue_full``, ``unauthorized``, ``forbidden``, …). An answer without that body (a proxy
    in between, a daemon too old) gets ``code`` ``http_<status>`` and its text as ``message``. Network failures
    are not answers: they raise ``httpx.TransportError``.
    """

    def __init__(self, status: int, code: str, message: str) -> None:
        super().__init__(f"HTTP {status} {code}: {message}")
        self.status = status
        self.code = code
        self.message = message

    @classmethod
    def from_response(cls, status: int, body: bytes) -> "ShiftError":
        """The error of an answer with ``status`` and ``body``."""
        text = body.decode("utf-8", errors="replace")
        try:
            detail = json.loads(text)["error"]
            return cls(status, str(detail["code"]), str(detail["message"]))
        except (ValueError, KeyError, TypeError):
            return cls(status, f"http_{status}", text.strip()[:2000])

    def __reduce__(self) -> Tuple[Type["ShiftError"], Tuple[int, str, str]]:
        """Keeps the fields through pickling (multiprocessing, pytest-xdist)."""
        return (type(self), (self.status, self.code, self.message))


def error_for(status: int, body: bytes) -> Optional[ShiftError]:
    """``None`` for a 2xx status, else the error it carries."""
    return None if 200 <= status < 300 else ShiftError.from_response(status, body)
