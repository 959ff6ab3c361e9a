"""The viewer's web app: the page, its static files, and a small JSON API over a
:class:`~scanlines.viewer.session.ViewerSession`.

=======================  ======  ===========================================================
``/``                    GET     the page
``/static/...``          GET     its script and style (shipped in the package: no network)
``/api/log``             GET     the log: name, format, scans read so far, poses, profile
``/api/methods``         GET     every method's parameters (type, domain, default) and presets
``/api/frame``           POST    ``{"index", "configs": [config, config?]}``: a scan's returns
                                 and, per configuration, its features and their differences
``/api/world``           POST    ``{"first", "last", "config"}``: a stretch in the world frame
``/api/config``          POST    ``{"config", "log"?}``: the configuration as a TOML file and
                                 as a ``scanlines run`` command line
=======================  ======  ===========================================================

A bad request (unknown scan, bad parameter, malformed body) is answered with status 400
and ``{"error": "one line"}``; the server goes on.
"""

from __future__ import annotations

from importlib.resources import files
from typing import Any

import numpy as np
import orjson
from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.requests import Request
from starlette.responses import FileResponse, Response
from starlette.routing import Mount, Route
from starlette.staticfiles import StaticFiles

from scanlines.config import ExtractionConfig
from scanlines.errors import ScanlinesError, one_line
from scanlines.viewer.session import ViewerSession, methods

__all__ = ["BadRequest", "create_app"]

STATIC = files("scanlines.viewer") / "static"


class BadRequest(ScanlinesError, ValueError):
    """A request the API cannot answer (its message is sent back)."""


class JSON(Response):
    media_type = "application/json"

    def render(self, content: Any) -> bytes:
        return orjson.dumps(content, default=_plain, option=orjson.OPT_SERIALIZE_NUMPY)


def _plain(value: Any) -> Any:
    """What orjson does not take itself: a strided numpy array (a column of points)."""
    if isinstance(value, np.ndarray):
        return np.ascontiguousarray(value)
    raise TypeError(f"cannot send {type(value).__name__} as JSON")


def create_app(session: ViewerSession) -> Starlette:
    """The viewer's ASGI app over ``session``."""

    async def page(request: Request) -> Response:
        return FileResponse(str(STATIC / "index.html"), headers={"Cache-Control": "no-store"})

    # Off the event loop: these wait for the configuration and for numba to load, while
    # the first frame's returns are served.
    async def log(request: Request) -> Response:
        return JSON(await run_in_threadpool(session.log))

    async def method_list(request: Request) -> Response:
        return JSON(await run_in_threadpool(methods))

    async def frame(request: Request) -> Response:
        body = await _body(request)
        index = _field(body, "index", int)
        configs = _field(body, "configs", list)
        return JSON(await run_in_threadpool(session.frame, index, configs))

    async def world(request: Request) -> Response:
        body = await _body(request)
        first, last = _field(body, "first", int), _field(body, "last", int)
        config = _field(body, "config", dict)
        return JSON(await run_in_threadpool(session.world, first, last, config))

    async def config(request: Request) -> Response:
        body = await _body(request)
        checked = ExtractionConfig.from_dict(_field(body, "config", dict), source="configuration")
        log_name = body.get("log") or str(session.store.path)
        return JSON({"toml": checked.to_toml(), "command": checked.command(str(log_name))})

    async def refused(request: Request, error: Exception) -> Response:
        return JSON({"error": one_line(str(error))}, status_code=400)

    async def failed(request: Request, error: Exception) -> Response:
        return JSON({"error": f"internal error: {one_line(repr(error))}"}, status_code=500)

    routes = [
        Route("/", page),
        Route("/api/log", log),
        Route("/api/methods", method_list),
        Route("/api/frame", frame, methods=["POST"]),
        Route("/api/world", world, methods=["POST"]),
        Route("/api/config", config, methods=["POST"]),
        Mount("/static", StaticFiles(directory=str(STATIC)), name="static"),
    ]
    return Starlette(routes=routes, exception_handlers={ScanlinesError: refused, Exception: failed})


async def _body(request: Request) -> dict[str, Any]:
    try:
        body = orjson.loads(await request.body())
    except orjson.JSONDecodeError as error:
        raise BadRequest(f"request body is not JSON: {error}") from None
    if not isinstance(body, dict):
        raise BadRequest(f"request body must be a JSON object, got {type(body).__name__}")
    return body


def _field(body: dict[str, Any], name: str, kind: type) -> Any:
    value = body.get(name)
    if not isinstance(value, kind) or isinstance(value, bool):
        raise BadRequest(f"request field {name!r} must be {kind.__name__}, got {value!r}")
    return value
