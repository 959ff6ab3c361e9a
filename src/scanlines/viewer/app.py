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
``/api/map``             POST    ``{"config"}``: the log's line map in the world frame (built
                                 on first request and kept; 409 for a log without poses)
``/api/config``          POST    ``{"config", "log"?}``: the configuration as a TOML file and
                                 as a ``scanlines run`` command line
=======================  ======  ===========================================================

A bad request (unknown scan, bad parameter, malformed body) is answered with status 400
and ``{"error": "one line"}``; the server goes on.

Only the viewer's own page may talk to it: a request whose ``Host`` header is not the
address the server listens on (or ``localhost`` with its port) is answered 403, so a web
page that rebinds its own name to 127.0.0.1 cannot read the log; a POST must say
``Content-Type: application/json`` (a cross-site form or ``text/plain`` POST, sent without
a preflight, gets 415), and a body over :data:`MAX_BODY_BYTES` gets 413 unread.
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
from scanlines.untrusted import quote
from scanlines.viewer.session import NoPoses, ViewerSession, methods

__all__ = ["MAX_BODY_BYTES", "BadRequest", "allowed_hosts", "create_app"]

STATIC = files("scanlines.viewer") / "static"

#: The largest request body the API reads (a frame request with two configurations is
#: under 2 KiB).
MAX_BODY_BYTES = 64 * 1024


class BadRequest(ScanlinesError, ValueError):
    """A request the API cannot answer (its message is sent back)."""


class Refused(BadRequest):
    """A request refused with its own status code."""

    def __init__(self, message: str, status: int) -> None:
        super().__init__(message)
        self.status = status


class JSON(Response):
    media_type = "application/json"

    def render(self, content: Any) -> bytes:
        return orjson.dumps(content, default=_plain, option=orjson.OPT_SERIALIZE_NUMPY)


def _plain(value: Any) -> Any:
    """What orjson does not take itself: a strided numpy array (a column of points)."""
    if isinstance(value, np.ndarray):
        return np.ascontiguousarray(value)
    raise TypeError(f"cannot send {type(value).__name__} as JSON")


def allowed_hosts(host: str, port: int) -> frozenset[str]:
    """The ``Host`` headers of requests to a server on ``host:port``: its address and
    ``localhost``, with the port."""
    return frozenset({f"{host}:{port}", f"localhost:{port}"})


class HostCheck:
    """ASGI middleware: 403 for an HTTP request whose ``Host`` header is not one of
    ``hosts`` (DNS rebinding: a page of another name reaching the loopback server)."""

    def __init__(self, app: Any, hosts: frozenset[str]) -> None:
        self.app = app
        self.hosts = frozenset(h.lower() for h in hosts)

    async def __call__(self, scope: Any, receive: Any, send: Any) -> None:
        if scope["type"] == "http":
            headers = dict(scope.get("headers") or ())
            host = headers.get(b"host", b"").decode("latin-1").lower()
            if host not in self.hosts:
                response = JSON({"error": f"host {host!r} is not this viewer's"}, 403)
                await response(scope, receive, send)
                return
        await self.app(scope, receive, send)


def create_app(session: ViewerSession, hosts: frozenset[str] | None = None) -> Any:
    """The viewer's ASGI app over ``session``; with ``hosts`` (see :func:`allowed_hosts`),
    requests with any other ``Host`` header are refused."""

    async def page(request: Request) -> Response:
        return FileResponse(str(STATIC / "index.html"), headers={"Cache-Control": "no-store"})

    # Off the event loop: these wait for the configuration and the sensor profile, while
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

    async def line_map(request: Request) -> Response:
        config = _field(await _body(request), "config", dict)
        return JSON(await run_in_threadpool(session.line_map, config))

    async def config(request: Request) -> Response:
        body = await _body(request)
        checked = ExtractionConfig.from_dict(_field(body, "config", dict), source="configuration")
        log_name = body.get("log") or str(session.store.path)
        return JSON({"toml": checked.to_toml(), "command": checked.command(str(log_name))})

    async def refused(request: Request, error: Exception) -> Response:
        status = error.status if isinstance(error, Refused | NoPoses) else 400
        return JSON({"error": one_line(str(error))}, status_code=status)

    async def failed(request: Request, error: Exception) -> Response:
        return JSON({"error": f"internal error: {one_line(repr(error))}"}, status_code=500)

    routes = [
        Route("/", page),
        Route("/api/log", log),
        Route("/api/methods", method_list),
        Route("/api/frame", frame, methods=["POST"]),
        Route("/api/world", world, methods=["POST"]),
        Route("/api/map", line_map, methods=["POST"]),
        Route("/api/config", config, methods=["POST"]),
        Mount("/static", StaticFiles(directory=str(STATIC)), name="static"),
    ]
    app = Starlette(routes=routes, exception_handlers={ScanlinesError: refused, Exception: failed})
    return app if hosts is None else HostCheck(app, hosts)


async def _read_limited(request: Request) -> bytes:
    declared = request.headers.get("content-length")
    if declared is not None and (not declared.isdigit() or int(declared) > MAX_BODY_BYTES):
        raise Refused(f"request body over {MAX_BODY_BYTES} bytes", 413)
    chunks, size = [], 0
    async for chunk in request.stream():
        size += len(chunk)
        if size > MAX_BODY_BYTES:
            raise Refused(f"request body over {MAX_BODY_BYTES} bytes", 413)
        chunks.append(chunk)
    return b"".join(chunks)


async def _body(request: Request) -> dict[str, Any]:
    media_type = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if media_type != "application/json":
        raise Refused(f"request body must be application/json, got {media_type!r}", 415)
    try:
        body = orjson.loads(await _read_limited(request))
    except orjson.JSONDecodeError as error:
        raise BadRequest(f"request body is not JSON: {error}") from None
    if not isinstance(body, dict):
        raise BadRequest(f"request body must be a JSON object, got {type(body).__name__}")
    return body


def _field(body: dict[str, Any], name: str, kind: type) -> Any:
    value = body.get(name)
    if not isinstance(value, kind) or isinstance(value, bool):
        raise BadRequest(f"request field {name!r} must be {kind.__name__}, got {quote(value)}")
    return value
