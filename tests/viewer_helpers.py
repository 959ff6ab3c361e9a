"""A real viewer server on a free local port, and JSON requests to it (viewer tests)."""

from __future__ import annotations

import contextlib
import gzip
import json
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from scanlines.data import sample
from scanlines.viewer import ScanStore, ViewerServer, ViewerSession


@contextlib.contextmanager
def serving(path: Path, **session_options: Any) -> Iterator[ViewerServer]:
    server = ViewerServer(ViewerSession(ScanStore(path), **session_options)).start()
    try:
        yield server
    finally:
        server.stop()


def request(server: ViewerServer, path: str, body: Any = None) -> tuple[int, Any]:
    """``(status, decoded JSON)`` of a GET (no body) or POST."""
    data = (
        None if body is None else (body if isinstance(body, bytes) else json.dumps(body).encode())
    )
    headers = {"Content-Type": "application/json"}
    message = urllib.request.Request(server.url + path.lstrip("/"), data, headers)
    try:
        with urllib.request.urlopen(message, timeout=120) as response:
            return response.status, json.loads(response.read())
    except urllib.error.HTTPError as error:
        return error.code, json.loads(error.read())


def long_carmen_log(folder: Path, copies: int) -> Path:
    """The shipped Intel excerpt's scans ``copies`` times over, as one CARMEN log."""
    lines = gzip.decompress(sample("intel").read_bytes()).splitlines(keepends=True)
    path = folder / f"intel_x{copies}.clf"
    with path.open("wb") as log:
        for _ in range(copies):
            log.writelines(lines)
    return path
