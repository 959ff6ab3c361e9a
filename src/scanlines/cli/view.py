"""``scanlines view``: the browser viewer of a log."""

from __future__ import annotations

from typing import Annotated

import typer

from scanlines.cli.common import ConfigMethodOption, ConfigOption, guarded, method_options
from scanlines.cli.logs import (
    AngleMinOption,
    AngleStepOption,
    ConventionOption,
    FovOption,
    LogArgument,
    MaxBeamsOption,
    OnErrorOption,
    ParamOption,
    PresetOption,
    ProfileOption,
    TopicOption,
    compiled_for,
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
) -> None:
    from scanlines.config import ExtractionConfig
    from scanlines.errors import LogFormatError
    from scanlines.sensor_profile import read_profile
    from scanlines.viewer.scan_store import ScanStore
    from scanlines.viewer.session import ViewerSession

    method, preset, params = method_options(method, preset, param, config)
    initial = ExtractionConfig(method, preset, params)
    initial.extractor()  # a bad configuration fails before the log is read
    profile = None if sensor_profile is None else read_profile(sensor_profile)
    options = reader_options(
        fov, angle_convention, topic, angle_min, angle_increment, on_error, max_beams
    )
    store = ScanStore(log, options)
    store.hold(after=HELD_SCANS)  # the rest of a long log waits until the page is prepared
    if not store.wait_for(1, FIRST_SCAN_SECONDS):
        store.close()
        raise LogFormatError(store.error or f"{log}: no scan to show")
    session = ViewerSession(store, profile, initial)
    _prepare(session, method)
    from scanlines.viewer.server import ViewerServer  # while the kernels load

    server = ViewerServer(session, host, port)
    typer.echo(f"scanlines view: {log.name} on {server.url} (Ctrl-C stops)")
    if not no_browser:
        _open_browser(server.url)
    try:
        server.run()
    finally:
        store.close()


def _prepare(session, method: str) -> None:
    """In the background, while the browser opens the page: measure the sensor profile and
    compile (or load) the chosen method's kernels; once the first frame is out, the other
    methods' too, so that choosing one in the page does not wait for it."""
    import threading

    from scanlines.extractor import method_names
    from scanlines.warm import warm_method

    def work() -> None:
        with compiled_for(method):
            session.prepare()
        session.first_frame.wait(FIRST_SCAN_SECONDS)  # loading kernels blocks other loads
        for name in method_names():
            if name != method:
                warm_method(name)

    threading.Thread(target=work, name="prepare", daemon=True).start()


def _open_browser(url: str) -> None:
    import webbrowser

    if not webbrowser.open(url):
        typer.echo("scanlines view: no browser found here; open the address above", err=True)
