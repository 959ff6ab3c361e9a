"""The browser viewer (``scanlines view``): scrub a log's scans, tune a method's parameters
and see the features change at once, compare two configurations.

A small ASGI app (:mod:`scanlines.viewer.app`, Starlette served by uvicorn) answers a
plain page shipped in the package (``static/``: no build step, no network); every frame
is extracted by the library (:mod:`scanlines.viewer.session`), from scans fetched on
demand (:mod:`scanlines.viewer.scan_store`).

From Python (a notebook, a test)::

    from scanlines.viewer import ScanStore, ViewerServer, ViewerSession
    server = ViewerServer(ViewerSession(ScanStore("intel.clf"))).start()
    print(server.url)
    ...
    server.stop()
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from scanlines.viewer.scan_store import ScanStore
    from scanlines.viewer.server import ViewerServer
    from scanlines.viewer.session import ViewerSession

__all__ = ["ScanStore", "ViewerServer", "ViewerSession"]

_HOMES = {"ScanStore": "scan_store", "ViewerServer": "server", "ViewerSession": "session"}


def __getattr__(name: str) -> Any:
    # Imported on first use: the web server's packages load while kernels are loading.
    if name in _HOMES:
        return getattr(importlib.import_module(f"scanlines.viewer.{_HOMES[name]}"), name)
    raise AttributeError(f"module 'scanlines.viewer' has no attribute {name!r}")
