"""Serving the viewer on a local port: in the foreground (``scanlines view``) or on a
background thread (tests, notebooks)."""

from __future__ import annotations

import socket
import threading
import time

import uvicorn

from scanlines.errors import ParameterError
from scanlines.viewer.app import allowed_hosts, create_app
from scanlines.viewer.session import ViewerSession

__all__ = ["ViewerServer"]


class ViewerServer:
    """The viewer of ``session`` on ``host:port`` (port 0: a free one, see :attr:`url`).

    The socket listens from construction, so the URL is known (and the port taken, and
    connections queued) before the server runs.
    """

    def __init__(self, session: ViewerSession, host: str = "127.0.0.1", port: int = 0) -> None:
        self.session = session
        self.socket = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.socket.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            self.socket.bind((host, port))
        except OSError as error:
            self.socket.close()
            reason = error.strerror or str(error)
            raise ParameterError(f"cannot serve the viewer on {host}:{port}: {reason}") from None
        self.socket.listen(128)  # connections wait from now on, not only once serving
        bound_host, bound_port = self.socket.getsockname()[:2]
        self.url = f"http://{bound_host}:{bound_port}/"
        app = create_app(session, allowed_hosts(bound_host, bound_port))
        config = uvicorn.Config(app, log_level="warning", lifespan="off")
        self._server = uvicorn.Server(config)
        self._thread: threading.Thread | None = None

    def run(self, *, prepare: bool = True) -> None:
        """Serve until Ctrl-C (or :meth:`shutdown` from another thread), preparing the
        session (:meth:`ViewerSession.prepare`) in the background meanwhile unless not
        ``prepare``."""
        if prepare:
            threading.Thread(target=self.session.prepare, name="prepare", daemon=True).start()
        self._server.run(sockets=[self.socket])

    def start(self, timeout: float = 10.0) -> ViewerServer:
        """Serve on a background thread; return once requests are answered."""
        self._thread = threading.Thread(target=self.run, name="viewer", daemon=True)
        self._thread.start()
        deadline = time.monotonic() + timeout
        while not self._server.started:
            if time.monotonic() > deadline or not self._thread.is_alive():
                raise RuntimeError(f"the viewer did not start on {self.url}")
            time.sleep(0.01)
        return self

    def shutdown(self) -> None:
        """Ask the server to stop, from any thread: :meth:`run` returns."""
        self._server.should_exit = True

    def stop(self) -> None:
        """Stop serving and close the log."""
        self._server.should_exit = True
        if self._thread is not None:
            self._thread.join(timeout=10)
        self.socket.close()
        self.session.store.close()

    def __enter__(self) -> ViewerServer:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()
