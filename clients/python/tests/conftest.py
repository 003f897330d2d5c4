"""Starts the real ``shiftd`` binary on loopback for the tests.

The binary: ``$SHIFTD_BIN`` when set; else the newer of ``target/release/shiftd`` and ``target/debug/shiftd``
under the repository root (``cargo test --workspace`` builds the debug one). A missing binary fails the tests
that need it; it never skips them.

Each daemon gets free ports for HTTP and Zenoh on 127.0.0.1, a temporary data dir, one plan worker, and a
config file whose ``[zenoh] listen`` is ``tcp/127.0.0.1:PORT`` (shiftd always turns multicast and gossip
scouting off). Its log goes to ``shiftd.log`` in the temporary folder and is printed when it fails to start.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import time
from pathlib import Path
from typing import Callable, Iterator, Optional, TypeVar

import httpx
import pytest

REPO_ROOT = Path(__file__).resolve().parents[3]


T = TypeVar("T")


def poll(f: Callable[[], Optional[T]], what: str, timeout: float) -> T:
    """Calls ``f`` every 50 ms until it gives a value other than None; fails naming ``what`` after ``timeout`` s."""
    deadline = time.monotonic() + timeout
    while True:
        v = f()
        if v is not None:
            return v
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.05)


def shiftd_binary() -> Path:
    """The shiftd executable the tests run (see the module doc)."""
    env = os.environ.get("SHIFTD_BIN")
    if env:
        path = Path(env)
        if not (path.is_file() and os.access(path, os.X_OK)):
            pytest.fail(f"SHIFTD_BIN={env} is not an executable file")
        return path
    found = [p for p in (REPO_ROOT / "target/release/shiftd", REPO_ROOT / "target/debug/shiftd") if p.is_file()]
    if not found:
        pytest.fail(
            f"no shiftd binary: set SHIFTD_BIN or build one (cargo build -p shiftd) under {REPO_ROOT / 'target'}"
        )
    return max(found, key=lambda p: p.stat().st_mtime)


def free_port() -> int:
    """A free TCP port on 127.0.0.1 (bound and released)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class Daemon:
    """A running ``shiftd serve``: ``url`` (HTTP) and ``zenoh_endpoint``."""

    def __init__(
        self,
        workdir: Path,
        *,
        token: str = "",
        zenoh: bool = True,
        demo: bool = True,
        queue_capacity: int = 8,
        retry_after_s: int = 5,
    ) -> None:
        self.workdir = workdir
        self.http_port = free_port()
        self.zenoh_port = free_port()
        self.url = f"http://127.0.0.1:{self.http_port}"
        self.zenoh_endpoint = f"tcp/127.0.0.1:{self.zenoh_port}"
        self.token = token
        self.log_path = workdir / "shiftd.log"
        config = workdir / "shiftd.toml"
        config.write_text(
            f"""
[http]
bind = "127.0.0.1:{self.http_port}"
auth_token = "{token}"
retry_after_s = {retry_after_s}

[store]
data_dir = "{(workdir / 'data').as_posix()}"

[jobs]
workers = 1
queue_capacity = {queue_capacity}
shutdown_grace_s = 0

[demo]
enabled = {str(demo).lower()}

[zenoh]
enabled = {str(zenoh).lower()}
mode = "peer"
listen = ["{self.zenoh_endpoint}"]
connect = []
""",
            encoding="utf-8",
        )
        self._log = open(self.log_path, "wb")
        self.proc = subprocess.Popen(
            [str(shiftd_binary()), "serve", "--config", str(config)],
            stdout=self._log,
            stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL,
            env={**os.environ, "RUST_LOG": os.environ.get("RUST_LOG", "warn,shiftd=info")},
        )
        try:
            self._wait_ready(timeout=90.0)
        except BaseException:
            self.stop()
            raise

    def _wait_ready(self, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise RuntimeError(f"shiftd exited with {self.proc.returncode}:\n{self.log_tail()}")
            try:
                if httpx.get(f"{self.url}/readyz", timeout=2.0).status_code == 200:
                    return
            except httpx.TransportError:
                pass
            time.sleep(0.05)
        raise RuntimeError(f"shiftd not ready after {timeout} s:\n{self.log_tail()}")

    def log_tail(self, lines: int = 40) -> str:
        """The last lines of the daemon's log."""
        self._log.flush()
        text = self.log_path.read_text(encoding="utf-8", errors="replace")
        return "\n".join(text.splitlines()[-lines:])

    def stop(self) -> Optional[int]:
        """SIGTERM, then SIGKILL after 20 s; returns the exit code."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout=20.0)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout=10.0)
        self._log.close()
        return self.proc.returncode


@pytest.fixture(scope="session")
def daemon(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Daemon]:
    """One shiftd for the session: demo site loaded, Zenoh on a free loopback port, no token."""
    d = Daemon(tmp_path_factory.mktemp("shiftd"))
    yield d
    code = d.stop()
    assert code == 0, f"shiftd exited with {code} on SIGTERM:\n{d.log_tail()}"


@pytest.fixture(scope="module")
def token_daemon(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Daemon]:
    """A shiftd with a bearer token on mutating routes (Zenoh off)."""
    d = Daemon(tmp_path_factory.mktemp("shiftd-token"), token="s3cret-token", zenoh=False)
    yield d
    d.stop()


@pytest.fixture(scope="session")
def busy_daemon(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Daemon]:
    """A shiftd whose plan queue holds one plan (one worker, Zenoh off) and asks 429s to wait 1 s."""
    d = Daemon(tmp_path_factory.mktemp("shiftd-busy"), zenoh=False, queue_capacity=1, retry_after_s=1)
    yield d
    d.stop()
