"""The viewer's scan store, session and JSON API, on a real server (uvicorn on a free port),
and ``scanlines view`` as a process."""

from __future__ import annotations

import http.client
import json
import re
import signal
import subprocess
import sys
import tracemalloc
import urllib.request
from pathlib import Path

import numpy as np
import pytest

from scanlines import Extractor
from scanlines.config import ExtractionConfig, load_config
from scanlines.data import sample
from scanlines.errors import ParameterError
from scanlines.io import open_log
from scanlines.runs.runner import log_profile
from scanlines.viewer import ScanStore, ViewerSession
from scanlines.viewer.app import MAX_BODY_BYTES, STATIC
from viewer_helpers import long_carmen_log, request, serving

FIXTURES = Path(__file__).parent / "io" / "fixtures"


# -- the scan store ------------------------------------------------------------------------


def test_store_gives_every_scan_of_the_log_by_index():
    with ScanStore(sample("freiburg")) as store, open_log(sample("freiburg")) as reader:
        originals = list(reader.enumerate())
        assert store.wait_for(len(originals) + 1) is False  # the log has no more
        assert store.count == len(originals)
        assert store.finished
        assert store.error is None
        for index in (len(originals) - 1, 0, 7, 123):  # out of order
            record, original = originals[index]
            scan = store.scan(index)
            assert store.record(index) == record
            np.testing.assert_array_equal(scan.ranges, original.ranges.astype(np.float32))
            assert scan.angle_increment == np.float32(original.angle_increment)
            assert scan.timestamp == original.timestamp
            np.testing.assert_array_equal(scan.pose, original.pose)


def test_store_scans_extract_as_the_log_does():
    extractor = Extractor("adaptive")
    with ScanStore(sample("intel")) as store, open_log(sample("intel")) as reader:
        for index, original in reader.enumerate():
            if index % 37 == 0:
                np.testing.assert_array_equal(
                    extractor(store.scan(index)).lines, extractor(original).lines
                )


def test_store_memory_does_not_grow_with_the_scans(tmp_path):
    log = long_carmen_log(tmp_path, copies=60)  # 18,000 scans
    tracemalloc.start()
    try:
        with ScanStore(log) as store:
            store.wait_for(10**9)
            for index in range(0, store.count, 97):
                store.scan(index)
            _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert store.count == 18_000
    # the scans' ranges alone are 13 MB as float32: only their places (8 bytes a scan) stay
    assert peak < 1e6, f"peak {peak / 1e6:.2f} MB while reading {store.count} scans"


def test_store_out_of_range_names_the_log_and_its_length():
    with ScanStore(sample("intel")) as store:
        with pytest.raises(ParameterError, match=r"scan 300 is out of range: intel.* 300 scans"):
            store.scan(300)
        with pytest.raises(ParameterError, match="integer >= 0"):
            store.scan(-1)


def test_store_keeps_the_scans_before_a_malformed_record():
    with ScanStore(FIXTURES / "carmen_not_a_number.log") as store:
        store.wait_for(10)
        assert store.count == 1
        assert store.finished
        assert "carmen_not_a_number.log" in store.error
        assert "line 3" in store.error
        assert len(store.scan(0)) == 5
        with pytest.raises(ParameterError, match="reading stopped"):
            store.scan(1)


# -- the session ---------------------------------------------------------------------------


@pytest.mark.parametrize("method", ["adaptive", "split_merge", "iepf", "ransac"])
def test_frame_features_are_those_of_the_library(method):
    profile = log_profile(sample("intel"), {})
    params = {"min_points": 7}
    with ScanStore(sample("intel")) as store:
        frame = ViewerSession(store).frame(42, [{"method": method, "params": params}])
        expected = Extractor(method, sensor_profile=profile, **params)(store.scan(42))
    (result,) = frame["results"]
    assert len(result["segments"]) == len(expected)
    starts = np.array([s["start"] for s in result["segments"]]).reshape(-1, 2)
    np.testing.assert_array_equal(starts, expected.lines[:, 2:4])
    np.testing.assert_array_equal(result["breakpoints"], expected.breakpoints)
    np.testing.assert_array_equal(result["corners"], expected.corners)
    assert frame["beams"] == 180
    assert frame["returns"] == int(store.scan(42).valid.sum())


def test_two_configurations_mark_what_only_one_has():
    with ScanStore(sample("intel")) as store:
        session = ViewerSession(store)
        same = session.frame(5, [{"method": "adaptive"}, {"method": "adaptive"}])
        differ = session.frame(5, [{"method": "adaptive"}, {"method": "split_merge"}])
    assert all(not r["differing_segments"] for r in same["results"])
    a, b = differ["results"]
    spans_a = {(s["first"], s["last"]) for s in a["segments"]}
    spans_b = {(s["first"], s["last"]) for s in b["segments"]}
    assert spans_a != spans_b
    assert {
        (a["segments"][k]["first"], a["segments"][k]["last"]) for k in a["differing_segments"]
    } == (spans_a - spans_b)


def test_a_frame_without_configurations_is_the_scan_alone():
    with ScanStore(sample("intel")) as store:
        session = ViewerSession(store)
        alone = session.frame(3, [])
        scan = store.scan(3)
    assert alone["results"] == []
    assert alone["noise"] is None
    np.testing.assert_array_equal(alone["x"], scan.points[:, 0])
    assert not session.first_frame.is_set()  # no kernel has run for the page yet


def test_a_configuration_given_later_is_waited_for_and_a_refused_one_fails():
    import threading

    with ScanStore(sample("intel")) as store:
        later = ViewerSession(store, config_later=True)
        assert later.frame(0, [])["returns"] > 0  # the returns need no configuration
        answers = []
        asking = threading.Thread(target=lambda: answers.append(later.log()["config"]))
        asking.start()
        asking.join(timeout=0.3)
        assert asking.is_alive()
        assert answers == []
        later.configure(ExtractionConfig("iepf"))
        asking.join(timeout=10)
        assert answers == [{"method": "iepf", "preset": None, "params": {}}]

        refused = ViewerSession(store, config_later=True)
        refused.refuse()
        with pytest.raises(ParameterError, match="configuration was refused"):
            refused.log()


def test_the_page_is_served_before_the_extraction_modules_load():
    # ``scanlines view`` serves the page (and the first scan's returns) while the
    # configuration is checked on another thread.
    code = (
        "import sys\n"
        "import scanlines.cli.commands, scanlines.cli.view\n"
        "from scanlines.data import sample\n"
        "from scanlines.viewer import ScanStore, ViewerSession\n"
        "from scanlines.viewer.server import ViewerServer\n"
        "import urllib.request, json\n"
        "store = ScanStore(sample('intel'))\n"
        "server = ViewerServer(ViewerSession(store, config_later=True)).start()\n"
        "request = urllib.request.Request(server.url + 'api/frame', method='POST',\n"
        "    data=json.dumps({'index': 0, 'configs': []}).encode(),\n"
        "    headers={'Content-Type': 'application/json'})\n"
        "frame = json.loads(urllib.request.urlopen(request, timeout=60).read())\n"
        "print(frame['returns'] > 0, 'scanlines.methods' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.stdout.split() == ["True", "False"], out.stderr


def test_world_view_moves_the_features_by_the_poses():
    with ScanStore(sample("intel")) as store:
        world = ViewerSession(store).world(0, 299, {"method": "adaptive"})
        np.testing.assert_allclose(world["path"][-1], store.scan(299).pose)
    assert world["scans"] == 300
    assert len(world["segments"]) > 300
    assert np.isfinite(world["segments"]).all()


FIXTURES = Path(__file__).parent / "io" / "fixtures"


@pytest.mark.parametrize(
    ("path", "options", "note"),
    [
        (sample("intel"), None, "poses as recorded in the log (may be raw odometry)"),
        (FIXTURES / "carmen_new_formats.log", {"message": "RAWLASER1"},
         "poses: raw odometry (the log's ODOM records)"),
        (FIXTURES / "intel_every5th_rows1098-1109.npz", None,
         "poses: raw odometry (the file's odom_pose)"),
    ],
)  # fmt: skip
def test_the_log_says_which_poses_the_world_view_stands_on(path, options, note):
    with ScanStore(path, options) as store:
        store.wait_for(10**9, timeout=60)
        assert store.finished
        assert ViewerSession(store).log()["poses_note"] == note


# -- the JSON API --------------------------------------------------------------------------


@pytest.fixture(scope="module")
def intel_server():
    with serving(sample("intel")) as server:
        yield server


def test_api_describes_the_log_and_the_methods(intel_server):
    status, log = request(intel_server, "/api/log")
    assert status == 200
    assert log["name"] == "intel_excerpt.clf.gz"
    assert log["poses"] is True
    assert log["config"] == {"method": "adaptive", "preset": None, "params": {}}
    status, methods = request(intel_server, "/api/methods")
    adaptive = next(m for m in methods if m["name"] == "adaptive")
    k = next(p for p in adaptive["params"] if p["name"] == "k")
    assert k["domain"]["type"] == "float"
    assert k["domain"]["low_open"] is True
    assert "paper" in adaptive["presets"]


@pytest.mark.parametrize(
    ("body", "message"),
    [
        ({"index": 300, "configs": [{}]}, "scan 300 is out of range: intel_excerpt.clf.gz has 300"),
        ({"index": -4, "configs": [{}]}, "scan index must be an integer >= 0"),
        ({"index": "7", "configs": [{}]}, "request field 'index' must be int"),
        ({"index": 1, "configs": [{"params": {"k": -1}}]}, "params.k: k must be a number in (0"),
        ({"index": 1, "configs": [{"params": {"nope": 1}}]}, "nope"),
        ({"index": 1, "configs": [{"method": "magic"}]}, "magic"),
        ({"index": 1, "configs": [{}, {}, {}]}, "one or two configurations, got 3"),
        ({"index": 1}, "request field 'configs' must be list"),
        (b"{not json", "request body is not JSON"),
        (b"[1, 2]", "request body must be a JSON object"),
    ],
)
def test_api_answers_a_bad_request_with_one_line_and_goes_on(intel_server, body, message):
    status, answer = request(intel_server, "/api/frame", body)
    assert status == 400
    assert message in answer["error"]
    assert "\n" not in answer["error"]
    assert request(intel_server, "/api/frame", {"index": 0, "configs": [{}]})[0] == 200


def _raw(server, method, path, headers, body=b""):
    """``(status, body)`` of a request sent with exactly these headers."""
    host, port = server.url.removeprefix("http://").rstrip("/").split(":")
    connection = http.client.HTTPConnection(host, int(port), timeout=60)
    try:
        connection.putrequest(method, path, skip_host=True, skip_accept_encoding=True)
        for name, value in headers.items():
            connection.putheader(name, value)
        connection.endheaders(body)
        response = connection.getresponse()
        return response.status, response.read()
    finally:
        connection.close()


@pytest.mark.parametrize("host", ["evil.com", "evil.com:{port}", "127.0.0.2:{port}", ""])
def test_api_refuses_a_host_other_than_its_own(intel_server, host):
    # DNS rebinding: a page of evil.com whose name now points at 127.0.0.1 sends its own Host
    port = intel_server.url.rstrip("/").rsplit(":", 1)[1]
    headers = {"Host": host.format(port=port)}
    for path in ("/", "/api/log"):
        status, answer = _raw(intel_server, "GET", path, headers)
        assert status == 403, path
        assert b"intel" not in answer  # neither the page nor the log's path


def test_api_answers_its_own_address_and_localhost(intel_server):
    port = intel_server.url.rstrip("/").rsplit(":", 1)[1]
    for host in (f"127.0.0.1:{port}", f"localhost:{port}", f"LOCALHOST:{port}"):
        status, answer = _raw(intel_server, "GET", "/api/log", {"Host": host})
        assert status == 200, host
        assert b"intel" in answer


@pytest.mark.parametrize(
    "content_type", [None, "text/plain", "application/x-www-form-urlencoded", "multipart/form-data"]
)
def test_api_post_needs_a_json_content_type(intel_server, content_type):
    port = intel_server.url.rstrip("/").rsplit(":", 1)[1]
    body = json.dumps({"index": 0, "configs": [{}]}).encode()
    headers = {"Host": f"127.0.0.1:{port}", "Content-Length": str(len(body))}
    if content_type is not None:
        headers["Content-Type"] = content_type
    status, answer = _raw(intel_server, "POST", "/api/frame", headers, body)
    assert status == 415
    assert b"application/json" in answer
    headers["Content-Type"] = "application/json; charset=utf-8"
    assert _raw(intel_server, "POST", "/api/frame", headers, body)[0] == 200


def test_api_refuses_a_body_over_the_limit_unread(intel_server):
    port = intel_server.url.rstrip("/").rsplit(":", 1)[1]
    body = b'{"index": 0, "configs": [], "pad": "' + b"x" * MAX_BODY_BYTES + b'"}'
    headers = {"Host": f"127.0.0.1:{port}", "Content-Type": "application/json"}
    declared = dict(headers, **{"Content-Length": str(len(body))})
    status, answer = _raw(intel_server, "POST", "/api/frame", declared, body)
    assert status == 413
    assert str(MAX_BODY_BYTES).encode() in answer
    # chunked, no declared length: cut off while reading
    chunked = dict(headers, **{"Transfer-Encoding": "chunked"})
    stream = b"".join(
        b"%x\r\n%s\r\n" % (len(piece), piece)
        for piece in (body[i : i + 8192] for i in range(0, len(body), 8192))
    )
    assert _raw(intel_server, "POST", "/api/frame", chunked, stream + b"0\r\n\r\n")[0] == 413
    assert request(intel_server, "/api/frame", {"index": 0, "configs": []})[0] == 200


def test_api_world_view_needs_poses(tmp_path):
    log = tmp_path / "scans.csv"
    log.write_text("1.0, 1.0, 1.0, 1.0\n2.0, 2.0, 2.0, 2.0\n")
    from scanlines.viewer import ViewerServer

    store = ScanStore(log, {"angle_min": -0.1, "angle_increment": 0.05})
    with ViewerServer(ViewerSession(store)) as server:
        status, answer = request(server, "/api/world", {"first": 0, "last": 1, "config": {}})
    assert status == 400
    assert "scans.csv has no poses" in answer["error"]


def library_map(path: Path, config: dict):
    """The line map ``scanlines map`` builds of the log at ``path`` with ``config``."""
    from scanlines.map import build_map

    checked = ExtractionConfig.from_dict(config)
    extractor = Extractor(
        checked.method, checked.preset, sensor_profile=log_profile(path, {}), **checked.params
    )
    with open_log(path) as reader:
        return build_map(reader.enumerate(), extractor).line_map.lines()


def test_api_map_is_the_library_map_of_the_log_in_the_world_frame(intel_server):
    config = {"method": "adaptive", "params": {"min_points": 6}}
    status, answer = request(intel_server, "/api/map", {"config": config})
    assert status == 200, answer
    lines = answer["lines"]
    assert len(lines) > 10
    ends = np.array([[line["start"], line["end"]] for line in lines])
    assert np.isfinite(ends).all()
    expected = library_map(sample("intel"), config)
    assert len(lines) == len(expected)
    np.testing.assert_allclose(ends[:, 0], expected.world_start)
    np.testing.assert_allclose(ends[:, 1], expected.world_end)
    assert answer["origin"] == list(expected.origin)
    assert [line["scans"] for line in lines] == expected.scans.tolist()
    assert [line["first_scan"] for line in lines] == expected.first_scan.tolist()
    assert [line["last_scan"] for line in lines] == expected.last_scan.tolist()
    assert answer["config"]["params"] == {"min_points": 6}
    assert answer["scans"] == 300


def test_api_map_is_built_once_per_configuration(intel_server):
    session = intel_server.session
    first = session.line_map({"method": "adaptive"})
    assert session.line_map({"method": "adaptive", "params": {}}) is first
    other = session.line_map({"method": "split_merge"})
    assert other is not first
    assert other["config"]["method"] == "split_merge"


def test_api_map_of_a_log_without_poses_says_why(tmp_path):
    log = tmp_path / "scans.csv"
    log.write_text("1.0, 1.0, 1.0, 1.0\n2.0, 2.0, 2.0, 2.0\n")
    from scanlines.viewer import ViewerServer

    store = ScanStore(log, {"angle_min": -0.1, "angle_increment": 0.05})
    with ViewerServer(ViewerSession(store)) as server:
        status, answer = request(server, "/api/map", {"config": {}})
        assert request(server, "/api/map", b"{}")[0] == 400  # no configuration
    assert status == 409
    assert answer == {"error": "scans.csv has no poses: no line map"}


@pytest.mark.parametrize("offset", [1e9 + 1.0, 1e15])
def test_api_map_of_a_log_beyond_the_maps_limit_is_a_400_naming_the_scan(tmp_path, offset):
    """Before: 500 (an ArrayMemoryError from 1e9 m)."""
    from map_shift import shifted_sample
    from scanlines.viewer import ViewerServer

    log = shifted_sample("intel", offset, tmp_path)
    with ViewerServer(ViewerSession(ScanStore(log, {}))) as server:
        status, answer = request(server, "/api/map", {"config": {}})
    assert status == 400
    assert re.fullmatch(
        rf"{re.escape(log.name)}: scan 0: the pose's x = \S+ m is beyond the map's limit "
        r"\|x\| <= 1e9 m",
        answer["error"],
    ), answer


def test_api_config_is_a_toml_file_and_a_command_line(intel_server, tmp_path):
    config = {
        "method": "split_merge",
        "preset": None,
        "params": {"min_points": 12, "min_length": 0.75},
    }
    status, answer = request(intel_server, "/api/config", {"config": config, "log": "run.clf"})
    assert status == 200
    saved = tmp_path / "chosen.toml"
    saved.write_text(answer["toml"])
    assert load_config(saved) == ExtractionConfig.from_dict(config)
    assert answer["command"].startswith("scanlines run run.clf --method split_merge")
    assert "--param min_points=12" in answer["command"]


def test_page_and_its_files_are_served_from_the_package(intel_server):
    with urllib.request.urlopen(intel_server.url) as page:
        html = page.read().decode()
    assert "/static/viewer.js" in html
    for name in ("viewer.js", "viewer.css"):
        with urllib.request.urlopen(intel_server.url + "static/" + name) as response:
            assert response.status == 200
            assert len(response.read()) > 1000
    for shipped in STATIC.iterdir():  # no network at run time: nothing fetched from elsewhere
        assert not re.search(r"(src|href)=\"(https?:)?//", shipped.read_text()), shipped.name
        assert "https://" not in shipped.read_text(), shipped.name


# -- scanlines view ------------------------------------------------------------------------


def _start_view(*args: str) -> tuple[subprocess.Popen, str]:
    process = subprocess.Popen(
        [sys.executable, "-m", "scanlines", "view", *map(str, args), "--no-browser"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    line = process.stdout.readline()
    match = re.search(r"on (http://127\.0\.0\.1:\d+/)", line)
    assert match, f"{line!r} / {process.stderr.read() if process.poll() is not None else ''}"
    return process, match.group(1)


def test_view_command_serves_the_log_until_interrupted():
    process, url = _start_view(sample("urg"), "--method", "split_merge", "--param", "min_points=12")
    try:
        with urllib.request.urlopen(url + "api/log", timeout=60) as response:
            assert b'"name":"urg_excerpt.dat.gz"' in response.read()
        with urllib.request.urlopen(url + "api/log", timeout=60) as response:
            assert b'"method":"split_merge"' in response.read()
        process.send_signal(signal.SIGINT)
        process.wait(timeout=60)  # the bound: a server that ignores SIGINT hangs past it
        assert process.returncode in (0, 130)
    finally:
        process.kill()


def test_a_port_in_use_is_refused_in_one_line():
    import socket

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        out = subprocess.run(
            [sys.executable, "-m", "scanlines", "view", str(sample("intel")), "--no-browser",
             "--port", str(port)],
            capture_output=True, text=True, timeout=120,
        )  # fmt: skip
    assert out.returncode == 2, out.stderr
    assert out.stderr.strip() == (
        f"scanlines: error: cannot serve the viewer on 127.0.0.1:{port}: Address already in use"
    )


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["missing.clf"], "missing.clf"),
        ([FIXTURES / "unknown.xyz"], "unknown.xyz"),
        ([sample("intel"), "--param", "k=-3"], "k must be"),
        ([FIXTURES / "empty.log"], "empty.log"),
    ],
)
def test_view_command_refuses_bad_input_in_one_line(args, needle):
    out = subprocess.run(
        [sys.executable, "-m", "scanlines", "view", *map(str, args), "--no-browser"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert out.returncode == 2, out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1, out.stderr
    assert needle in lines[0], out.stderr
