"""``scanlines view``: the browser viewer of a log."""

from __future__ import annotations

from typing import Annotated

import typer

from scanlines.cli.common import (
    AngleMinOption,
    AngleStepOption,
    ConfigMethodOption,
    ConfigOption,
    ConventionOption,
    FovOption,
    LogArgument,
    MaxBeamsOption,
    OnErrorOption,
    ParamOption,
    PresetOption,
    ProfileOption,
    RangeMaxOption,
    TopicOption,
    guarded,
    method_options,
    reader_options,
)

#: How long the command waits for the log's first scan before giving up.
FIRST_SCAN_SECONDS = 60.0
#: Scans read before the first frame is prepared (the rest would slow it, on two cores).
HELD_SCANS = 1000


def register(app: typer.Typer) -> None:
    app.command(
        "view",
        help="Open a log in the browser: scrub its scans, tune a method, compare two "
        "configurations.",
    )(guarded(view_command))


def view_command(
    log: LogArgument,
    method: ConfigMethodOption = None,
    preset: PresetOption = None,
    param: ParamOption = None,
    config: ConfigOption = None,
    sensor_profile: ProfileOption = None,
    host: Annotated[
        str, typer.Option(help="Address to serve on (the default: this machine only; no login).")
    ] = "127.0.0.1",
    port: Annotated[int, typer.Option(help="Port (0: a free one).", min=0, max=65535)] = 0,
    no_browser: Annotated[
        bool, typer.Option("--no-browser", help="Print the address; do not open a browser.")
    ] = False,
    on_error: OnErrorOption = "fail",
    max_beams: MaxBeamsOption = None,
    fov: FovOption = None,
    angle_convention: ConventionOption = None,
    topic: TopicOption = None,
    angle_min: AngleMinOption = None,
    angle_increment: AngleStepOption = None,
    range_max: RangeMaxOption = None,
) -> None:
    from scanlines.errors import LogFormatError
    from scanlines.viewer.scan_store import ScanStore
    from scanlines.viewer.server import ViewerServer
    from scanlines.viewer.session import ViewerSession

    method, preset, params = method_options(method, preset, param, config)
    profile = None
    if sensor_profile is not None:
        from scanlines.sensor.profile import read_profile

        profile = read_profile(sensor_profile)
    options = reader_options(
        fov, angle_convention, topic, angle_min, angle_increment, on_error, max_beams, range_max
    )
    store = ScanStore(log, options)
    store.hold(after=HELD_SCANS)  # the rest of a long log waits until the page is prepared
    if not store.wait_for(1, FIRST_SCAN_SECONDS):
        store.close()
        raise LogFormatError(store.error or f"{log}: no scan to show")
    # The page is served (and the first scan's returns drawn) while the configuration is
    # checked and the sensor profile measured.
    session = ViewerSession(store, profile, config_later=True)
    server = ViewerServer(session, host, port)
    typer.echo(f"scanlines view: {log.name} on {server.url} (Ctrl-C stops)")
    preparing = _Preparation(session, server, (method, preset, params), not no_browser)
    try:
        server.run(prepare=False)  # _Preparation prepares
    finally:
        store.close()
    if preparing.error is not None:
        raise preparing.error


class _Preparation:
    """In the background, while the page is served: check the configuration (a bad one
    stops the server, and the command fails with it), open the browser and measure the
    sensor profile."""

    def __init__(self, session, server, configuration, open_browser: bool) -> None:
        import threading

        self.error: Exception | None = None
        self._session, self._server = session, server
        self._configuration, self._open_browser = configuration, open_browser
        threading.Thread(target=self._work, name="prepare", daemon=True).start()

    def _work(self) -> None:
        from scanlines.config import ExtractionConfig

        method, preset, params = self._configuration
        try:
            initial = ExtractionConfig(method, preset, params)
            initial.extractor()
        except Exception as error:  # raised again by the command, once the server stopped
            self.error = error
            self._session.refuse()
            self._server.shutdown()
            return
        self._session.configure(initial)
        if self._open_browser:
            _open_browser(self._server.url)
        self._session.prepare()


def _open_browser(url: str) -> None:
    import webbrowser

    if not webbrowser.open(url):
        typer.echo("scanlines view: no browser found here; open the address above", err=True)
