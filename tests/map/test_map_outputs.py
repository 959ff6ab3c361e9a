"""What the map commands write: strict JSON (never NaN), files that say their frame and
origin (GeoJSON, JSON, SVG in metres), one line naming the output when it cannot be
written, the poses the map used, and TUM files with conflicting duplicate timestamps."""

from __future__ import annotations

import json
import os
import shutil
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from map_shift import shifted_sample
from scanlines.cli.commands import app
from scanlines.data import sample
from scanlines.map.poses import PoseError, read_tum
from scanlines.scan import Scan

SVG = "{http://www.w3.org/2000/svg}"


def strict(text: str):
    """``json.loads`` that refuses NaN and infinities (bare ``NaN``, ``Infinity``)."""

    def refuse(constant: str):
        raise ValueError(f"not JSON: {constant}")

    return json.loads(text, parse_constant=refuse)


def invoke(*args: str):
    return CliRunner().invoke(app, [str(a) for a in args])


def test_eval_map_without_align_writes_strict_json(tmp_path):
    """Before: ``"localised_coverage": NaN`` in every map_eval.json without --align."""
    done = invoke("eval", "map", sample("intel"), "--scans", "100", "--out", tmp_path)
    assert done.exit_code == 0, done.output
    score = strict((tmp_path / "map_eval.json").read_text())
    assert score["localised_coverage"] is None
    assert score["localised_median_distance"] is None
    assert 0.5 < score["coverage"] <= 1.0


def test_dumps_never_writes_a_bare_nan_or_infinity():
    from scanlines.map.export import dumps

    text = dumps({"a": float("nan"), "b": [float("inf"), -float("inf")], "c": np.float64(1.5)})
    assert strict(text) == {"a": None, "b": ["inf", "-inf"], "c": 1.5}


@pytest.fixture(scope="module")
def far_maps(tmp_path_factory):
    """The Intel excerpt at the origin and at 1e7 m, mapped as GeoJSON, JSON and SVG."""
    folder = tmp_path_factory.mktemp("far")
    written = {}
    for offset in (0.0, 1e7):
        log = shifted_sample("intel", offset, folder)
        for suffix in (".geojson", ".json", ".svg"):
            out = folder / f"map-{offset:g}{suffix}"
            done = invoke("map", log, "--out", out, "--scans", "150")
            assert done.exit_code == 0, done.output
            written[offset, suffix] = out
    return written


def test_geojson_far_from_the_origin_is_strict_finite_and_says_its_frame(far_maps):
    """Before: a feature with NaN coordinates at 1e7 m, and nothing saying the numbers are
    not degrees."""
    near = strict(far_maps[0.0, ".geojson"].read_text())
    far = strict(far_maps[1e7, ".geojson"].read_text())
    ends = [np.array([f["geometry"]["coordinates"] for f in d["features"]]) for d in (near, far)]
    assert ends[1].shape == ends[0].shape
    assert np.isfinite(ends[1]).all()
    np.testing.assert_allclose(ends[1] - 1e7, ends[0], rtol=0, atol=1e-6)
    for document, offset in ((near, 0.0), (far, 1e7)):
        assert "not WGS84" in document["frame"]["coordinates"]
        assert document["frame"]["units"] == "metre"
        assert document["frame"]["origin"] == [offset + 0.0, offset - 13.0]
        assert document["crs"]["properties"]["name"].startswith("LOCAL_CS[")


def test_gdal_reads_the_geojson_as_a_local_frame_in_metres(far_maps):
    pyogrio = pytest.importorskip("pyogrio")
    info = pyogrio.read_info(far_maps[1e7, ".geojson"])
    assert info["crs"].startswith("LOCAL_CS[")
    assert 'UNIT["metre",1]' in info["crs"]
    assert info["geometry_type"] == "LineString"


def test_json_map_states_its_origin_and_keeps_rho_in_the_local_frame(far_maps):
    near = strict(far_maps[0.0, ".json"].read_text())
    far = strict(far_maps[1e7, ".json"].read_text())
    assert far["frame"]["origin"] == [1e7, 1e7 - 13.0]
    rho = [np.array([line["rho"] for line in d["lines"]]) for d in (near, far)]
    np.testing.assert_allclose(rho[1], rho[0], rtol=0, atol=1e-6)
    assert far["poses"] == "the log's poses, unaligned"
    assert "raw odometry drifts" in far["poses_note"]
    assert "--poses" in far["poses_note"]


def test_svg_is_in_metres_about_the_local_origin(far_maps):
    """Before: pixels (20 per metre) from the map's corner, no origin."""
    root = ET.parse(far_maps[1e7, ".svg"]).getroot()
    assert root.get("data-units") == "m"
    origin = np.array([float(root.get("data-origin-x")), float(root.get("data-origin-y"))])
    np.testing.assert_array_equal(origin, [1e7, 1e7 - 13.0])
    assert "metres" in root.find(f"{SVG}desc").text
    x, y, width, height = (float(v) for v in root.get("viewBox").split())
    ends = np.array(
        [[float(e.get(k)) for k in ("x1", "y1", "x2", "y2")] for e in root.iter(f"{SVG}line")]
    ).reshape(-1, 2)
    assert x <= ends[:, 0].min()
    assert ends[:, 0].max() <= x + width
    assert y <= ends[:, 1].min()
    assert ends[:, 1].max() <= y + height
    assert max(width, height) < 100  # metres, not pixels
    world = np.column_stack((ends[:, 0], -ends[:, 1])) + origin
    geojson = strict(far_maps[1e7, ".geojson"].read_text())
    expected = np.array([f["geometry"]["coordinates"] for f in geojson["features"]])
    np.testing.assert_allclose(world, expected.reshape(-1, 2), atol=1e-4)


def test_the_summary_says_the_map_uses_the_logs_poses_unaligned(tmp_path):
    """Before: only "(the log's poses)", on a raw-odometry log that maps as a fan."""
    done = invoke("map", sample("intel"), "--out", tmp_path / "m.json", "--scans", "60")
    assert done.exit_code == 0, done.output
    assert "(the log's poses, unaligned)" in done.stdout
    (note,) = [line for line in done.stderr.splitlines() if line.startswith("poses: ")]
    assert "cannot say whether they are corrected" in note
    assert "raw odometry drifts" in note
    assert "--poses FILE" in note


# -- outputs that cannot be written ---------------------------------------------------------


def in_child(args: list[str], *, user: int | None = None) -> tuple[int, str, str]:
    """Run the command in a forked process (as ``user`` if given: a root process writes
    into read-only folders); its exit code, stdout and stderr."""
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        try:
            os.close(read)
            if user is not None:
                os.setgid(user)
                os.setuid(user)
            result = CliRunner().invoke(app, args)
            payload = [result.exit_code, result.stdout, result.stderr]
            with os.fdopen(write, "w") as pipe:
                json.dump(payload, pipe)
        finally:
            os._exit(0)
    os.close(write)
    with os.fdopen(read) as pipe:
        text = pipe.read()
    os.waitpid(pid, 0)
    code, stdout, stderr = json.loads(text)
    return code, stdout, stderr


@pytest.fixture
def read_only_folder():
    """A folder no one but root may write into, inside a folder any user may enter."""
    outer = Path(tempfile.mkdtemp(prefix="scanlines-ro-"))
    outer.chmod(0o755)
    folder = outer / "read-only"
    folder.mkdir()
    folder.chmod(0o555)
    (outer / "open").mkdir()
    (outer / "open").chmod(0o777)  # for the outputs that can be written
    yield folder
    folder.chmod(0o755)
    shutil.rmtree(outer)


NOBODY = 65534


@pytest.mark.parametrize("what", ["map", "plot", "eval"])
def test_a_read_only_folder_is_named_in_one_line(tmp_path, read_only_folder, what):
    """Before: ``[Errno 13] Permission denied: '.../.map.geojson.<pid>.<hex>.tmp'``."""
    log = str(sample("intel"))
    target = read_only_folder / {"map": "map.geojson", "plot": "map.png", "eval": "scores"}[what]
    args = {
        "map": ["map", log, "--out", str(target), "--scans", "30"],
        "plot": ["map", log, "--out", str(read_only_folder.parent / "open" / "m.json"),
                 "--plot", str(target),
                 "--scans", "30"],
        "eval": ["eval", "map", log, "--out", str(target), "--scans", "30"],
    }[what]  # fmt: skip
    warm = invoke("map", log, "--out", tmp_path / "warm.json", "--scans", "5", "--plot",
                  tmp_path / "warm.png")  # fmt: skip
    assert warm.exit_code == 0, warm.output  # matplotlib loaded here
    code, _, stderr = in_child(args, user=NOBODY if os.geteuid() == 0 else None)
    assert code == 2, stderr
    shown = target / "map_eval.json" if what == "eval" else target
    # Written whole or not at all: the shared atomic writer names the output it commits.
    name = {"map": "the output", "plot": "the figure", "eval": "the map's score"}[what]
    assert stderr.strip().splitlines()[-1] == (
        f"scanlines: error: {shown}: cannot write {name} "
        "(PermissionError: [Errno 13] Permission denied)"
    )
    assert list(read_only_folder.iterdir()) == []


def test_a_full_disk_is_named_in_one_line(tmp_path, monkeypatch):
    """The map's temporary file opened on /dev/full: the write fails as on a full disk.
    Before: a bare ``[Errno 28] No space left on device``."""
    import scanlines.outputs

    real_open = open

    def full_disk(path, mode="r", *args, **kwargs):
        if str(path).endswith(".tmp") and "x" in mode:
            return real_open("/dev/full", mode.replace("x", "w"), *args, **kwargs)
        return real_open(path, mode, *args, **kwargs)

    monkeypatch.setattr(scanlines.outputs, "open", full_disk, raising=False)
    out = tmp_path / "map.geojson"
    done = invoke("map", sample("intel"), "--out", out, "--scans", "30")
    assert done.exit_code == 2
    assert done.stderr.strip().splitlines()[-1] == (
        f"scanlines: error: {out}: cannot write the output "
        "(OSError: [Errno 28] No space left on device)"
    )
    scores = tmp_path / "scores"
    done = invoke("eval", "map", sample("intel"), "--out", scores, "--scans", "30")
    assert done.exit_code == 2
    assert done.stderr.strip().splitlines()[-1] == (
        f"scanlines: error: {scores / 'map_eval.json'}: cannot write the output "
        "(OSError: [Errno 28] No space left on device)"
    )
    assert list(tmp_path.iterdir()) == [scores]
    assert list(scores.iterdir()) == []


# -- TUM files ------------------------------------------------------------------------------


def test_tum_lines_with_one_timestamp_and_two_poses_are_refused(tmp_path):
    """Before: accepted silently (the first after a stable sort was used)."""
    path = tmp_path / "poses.tum"
    path.write_text(
        "# timestamp tx ty tz qx qy qz qw\n"
        "1.0 0 0 0 0 0 0 1\n"
        "2.0 1 0 0 0 0 0 1\n"
        "3.0 2 0 0 0 0 0 1\n"
        "2.0 1.5 0 0 0 0 0 1\n"
    )
    with pytest.raises(
        PoseError,
        match=r"poses\.tum: lines 3 and 5: two different poses at the same timestamp 2\.0",
    ):
        read_tum(path)
    turned = tmp_path / "turned.tum"
    turned.write_text("1.0 0 0 0 0 0 0 1\n1.0 0 0 0 0 0 1 0\n")
    with pytest.raises(PoseError, match=r"turned\.tum: lines 1 and 2"):
        read_tum(turned)
    done = invoke("map", sample("intel"), "--out", tmp_path / "m.json", "--poses", path)
    assert done.exit_code == 2
    assert (
        done.stderr.strip().splitlines()[-1].startswith(f"scanlines: error: {path}: lines 3 and 5")
    )


def test_tum_lines_repeating_one_pose_are_accepted_once(tmp_path):
    path = tmp_path / "poses.tum"
    path.write_text(
        "1.0 0 0 0 0 0 0 1\n2.0 1 0 0 0 0 0 1\n2.0 1.0 0 0.3 0 0 0 1\n2.0 1 0 0 0 0 0 -1\n"
        "3.0 2 0 0 0 0 0 1\n"
    )
    trajectory = read_tum(path)
    assert trajectory.times.tolist() == [1.0, 2.0, 3.0]
    assert trajectory(0, Scan([1.0], 0.0, 0.1, timestamp=2.0)) == (1.0, 0.0, 0.0)


def test_a_tum_pose_beyond_the_limit_is_refused_with_its_line(tmp_path):
    path = tmp_path / "poses.tum"
    path.write_text("1.0 0 0 0 0 0 0 1\n2.0 1e15 0 0 0 0 0 1\n")
    with pytest.raises(
        PoseError, match=r"poses\.tum: line 2: the pose's x = 1000000000000000\.0 m is beyond"
    ):
        read_tum(path)
