"""Sensor profiles: the noise measured from the data, and what every output carries."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from scanlines import Extractor, Scan, extract
from scanlines.cli import app
from scanlines.data import sample
from scanlines.evaluation.scenes import make_scene
from scanlines.extraction import END_KINDS
from scanlines.io import open_log
from scanlines.runs.runner import run_log_to_file
from scanlines.sensor.profile import ProfileError, SensorProfile, estimate_profile, read_profile
from scanlines.sim import get_sensor
from scenes import scan_of

SAMPLES = ("intel", "freiburg", "urg")


def _scans(name: str) -> list[Scan]:
    return list(open_log(sample(name)))


def test_calibration_recovers_a_known_noise_curve_in_every_range_bin():
    # urg04lx: sigma = max(1 cm, 1 % of the range) and 1 mm quantisation
    sensor = get_sensor("urg04lx")
    scans = [make_scene("urg04lx", i, seed=11).scan for i in range(120)]
    profile = estimate_profile(scans)
    assert len(profile.noise_bins) >= 4
    for bin_ in profile.noise_bins:
        true = float(sensor.noise.effective_sigma(np.array([bin_.range]))[0])
        assert bin_.sigma == pytest.approx(true, rel=0.15), (bin_, true)
        assert 0.0 < bin_.error < 0.2 * bin_.sigma
    assert profile.noise_per_metre == pytest.approx(0.01, rel=0.3)


def test_calibration_sees_constant_noise_as_constant():
    scans = [make_scene("lms_05deg", i, seed=11).scan for i in range(60)]
    profile = estimate_profile(scans)
    true = float(get_sensor("lms_05deg").noise.effective_sigma(np.array([2.0]))[0])
    for r in (1.0, 4.0):
        assert float(profile.sigma_at(r)) == pytest.approx(true, rel=0.15)


def _nees(sigma: float, n: int = 300) -> float:
    """Mean NEES of (rho, alpha) of a 3 m wall at 0.5 deg over ``n`` noisy scans."""
    values = []
    for seed in range(n):
        scan = scan_of(
            [((3.0, -2.0), (3.0, 2.0))], fov_deg=70, step_deg=0.5, sigma=sigma, seed=seed
        )
        result = extract(scan)
        k = int(np.argmax(result.n_points))
        error = np.array(
            [result.lines[k, 0] - 3.0, math.remainder(result.lines[k, 1], 2 * math.pi)]
        )
        values.append(float(error @ np.linalg.solve(result.covariances[k], error)))
    return float(np.mean(values))


@pytest.mark.parametrize("sigma", [0.003, 0.03])
def test_covariances_are_consistent_at_low_and_high_noise(sigma):
    assert 0.8 * 2 <= _nees(sigma) <= 1.25 * 2


def test_a_rough_wall_gets_a_wider_covariance_than_a_smooth_one():
    smooth = scan_of([((3.0, -2.0), (3.0, 2.0))], fov_deg=70, step_deg=0.5, sigma=0.001, seed=1)
    rough = scan_of([((3.0, -2.0), (3.0, 2.0))], fov_deg=70, step_deg=0.5, sigma=0.03, seed=1)
    a, b = extract(smooth), extract(rough)
    assert b.covariances[0, 0, 0] > 50 * a.covariances[0, 0, 0]


@pytest.mark.xfail(
    strict=True,
    reason="target of the accuracy issue not reached: 149 of 167 (0.89) on 2026-12-02; "
    "breakpoints on walls near grazing incidence with 1 % range noise",
)
def test_long_walls_of_a_urg_like_log_come_out_whole():
    """At least 90 % of the true segments of 1 m or more are covered by one segment."""
    whole = total = 0
    for index in range(40):
        case = make_scene("urg04lx", index, seed=5)
        scan, truth = case.scan, case.truth
        result = extract(scan)
        seg = truth.segments
        for k in range(len(seg.first)):
            if np.hypot(*(seg.end[k] - seg.start[k])) < 1.0 or seg.first[k] > seg.last[k]:
                continue
            beams = np.arange(seg.first[k], seg.last[k] + 1)
            beams = beams[scan.valid[beams] & truth.true_return[beams]]
            if beams.size < 5:
                continue
            total += 1
            inside = [
                np.count_nonzero((beams >= f) & (beams <= last))
                for f, last in zip(result.first, result.last, strict=True)
            ]
            whole += max(inside, default=0) >= 0.9 * beams.size
    assert total >= 100
    assert whole >= 0.9 * total, (whole, total)


@pytest.mark.parametrize("name", SAMPLES)
def test_float32_input_gives_the_same_features_as_float64(name):
    same = 0
    scans = _scans(name)
    for scan in scans:
        narrow = Scan(
            scan.ranges.astype(np.float32),
            np.float32(scan.angle_min),
            np.float32(scan.angle_increment),
            np.float32(scan.range_min),
            np.float32(scan.range_max),
        )
        a, b = extract(scan), extract(narrow)
        same += (
            np.array_equal(a.first, b.first)
            and np.array_equal(a.lines, b.lines)
            and np.array_equal(a.breakpoints, b.breakpoints)
            and np.array_equal(a.corners, b.corners)
        )
    assert same >= 0.995 * len(scans)


def test_the_same_profile_gives_the_same_features_everywhere(tmp_path):
    scans = _scans("freiburg")[:80]
    profile = estimate_profile(scans)
    extractor = Extractor(sensor_profile=profile)
    one_by_one = [extractor(scan) for scan in scans]
    stack = np.stack([scan.ranges for scan in scans])
    first = scans[0]
    batch = extractor.batch(
        stack, first.angle_min, first.angle_increment, first.range_min, first.range_max
    )
    out = tmp_path / "run.jsonl"
    with open_log(sample("freiburg")) as reader:
        run_log_to_file(reader, extractor, out, scans=slice(0, 80))
    records = [json.loads(line) for line in out.read_text().splitlines()]
    for a, b, record in zip(one_by_one, batch, records, strict=True):
        assert np.array_equal(a.lines, b.lines)
        assert np.array_equal(a.covariances, b.covariances)
        assert [s["first"] for s in record["segments"]] == a.first.tolist()
        assert [s["rho"] for s in record["segments"]] == a.lines[:, 0].tolist()
    meta = json.loads((tmp_path / "run.jsonl.meta.json").read_text())
    assert SensorProfile.from_dict(meta["sensor_profile"]) == profile


def test_a_profile_round_trips_and_bad_files_are_named(tmp_path):
    profile = estimate_profile(_scans("intel")[:50], source="intel")
    path = profile.save(tmp_path / "intel.json")
    assert read_profile(path) == profile
    assert Extractor(sensor_profile=path).sensor_profile == profile
    broken = tmp_path / "broken.json"
    broken.write_text(
        '{"format": "scanlines-sensor-profile/1", "noise_sigma0": "x", "noise_per_metre": 0}'
    )
    with pytest.raises(ProfileError, match=r"broken\.json.*noise_sigma0"):
        read_profile(broken)
    with pytest.raises(ProfileError, match="no such file or directory"):
        read_profile(tmp_path / "missing.json")


def test_calibrate_writes_a_profile_and_run_uses_it(tmp_path):
    runner = CliRunner()
    profile_path = tmp_path / "urg.json"
    log = str(sample("urg"))
    result = runner.invoke(
        app, ["calibrate", log, "--out", str(profile_path), "--plot", str(tmp_path / "n.png")]
    )
    assert result.exit_code == 0, result.output
    assert (tmp_path / "n.png").stat().st_size > 0
    profile = read_profile(profile_path)
    assert profile.beams == 683
    assert 0.4 < profile.dropout_rate < 0.8
    out = tmp_path / "x.csv"
    result = runner.invoke(
        app, ["run", log, "--out", str(out), "--sensor-profile", str(profile_path)]
    )
    assert result.exit_code == 0, result.output
    header = out.read_text().splitlines()[0].split(",")
    covariance = header.index("var_rho")
    assert header[covariance : covariance + 5] == [
        "var_rho", "cov_rho_alpha", "var_alpha", "start_kind", "end_kind"
    ]  # fmt: skip
    npz = tmp_path / "one.npz"
    scan = _scans("urg")[0]
    np.savez(
        npz, ranges=scan.ranges, angle_min=scan.angle_min, angle_increment=scan.angle_increment
    )
    result = runner.invoke(
        app, ["extract", str(npz), "--sensor-profile", str(profile_path), "--json"]
    )
    assert result.exit_code == 0, result.output
    expected = Extractor(sensor_profile=profile)(
        Scan(scan.ranges, scan.angle_min, scan.angle_increment)
    )
    assert [s["first"] for s in json.loads(result.output)["segments"]] == expected.first.tolist()
    result = runner.invoke(app, ["run", log, "--scans", ":5", "--out", str(tmp_path / "y.jsonl")])
    assert result.exit_code == 0
    assert "sensor profile: measured from the first 5 scans" in result.output


def test_segment_ends_say_what_ends_them():
    # a wall x = 3, a gap of missing beams in it, then a nearer wall x = 2
    bearings = -0.6 + 0.01 * np.arange(120)
    ranges = np.where(np.arange(120) < 80, 3.0, 2.0) / np.cos(bearings)
    ranges[40:45] = np.inf
    result = extract(Scan(ranges, -0.6, 0.01))
    kinds = [(s.start_kind, s.end_kind) for s in result.segments]
    assert kinds[0] == ("edge", "gap")
    assert kinds[1] == ("gap", "occluded")
    assert kinds[2] == ("jump", "edge")
    assert set(END_KINDS) >= {k for pair in kinds for k in pair}


def test_extractions_and_extractors_with_a_profile_pickle():
    import pickle

    scans = _scans("intel")[:5]
    extractor = Extractor(sensor_profile=estimate_profile(scans))
    again = pickle.loads(pickle.dumps(extractor))
    assert again.sensor_profile == extractor.sensor_profile
    for scan in scans:
        a = extractor(scan)
        b = pickle.loads(pickle.dumps(a))
        assert np.array_equal(b.lines, a.lines)
        assert np.array_equal(b.end_kinds, a.end_kinds)
        assert np.array_equal(again(scan).lines, a.lines)
        assert dict(b.params) == dict(a.params)


def _robot_logs(tmp_path, mounting):
    """The Intel excerpt's first scans driven along a curve, logged twice: as FLASER
    records with the laser's and the robot's pose, and as ODOM + RAWLASER1 records (the
    robot's pose only)."""
    from scanlines.geometry.poses import compose

    flaser, rawlaser = [], []
    for k, scan in enumerate(_scans("intel")[:12]):
        robot = (0.4 * k, 0.1 * k * k, 0.05 * k - 0.3)
        laser = compose(robot, mounting)
        ranges = " ".join(f"{r:.3f}" for r in scan.ranges)
        n, t = len(scan.ranges), 10.0 + k
        poses = " ".join(f"{v:.9f}" for v in (*laser, *robot))
        flaser.append(f"FLASER {n} {ranges} {poses} {t} host {t}")
        odom = " ".join(f"{v:.9f}" for v in robot)
        rawlaser.append(f"ODOM {odom} 0 0 0 {t} host {t}")
        step = math.pi / n
        rawlaser.append(
            f"RAWLASER1 0 {-math.pi / 2} {math.pi} {step} 80.0 0.01 0 {n} {ranges} 0 {t} host {t}"
        )
    (tmp_path / "flaser.log").write_text("\n".join(flaser) + "\n")
    (tmp_path / "rawlaser.log").write_text("\n".join(rawlaser) + "\n")
    return tmp_path / "flaser.log", tmp_path / "rawlaser.log"


def test_calibrate_measures_the_mounting_and_world_frame_runs_use_it(tmp_path):
    mounting = (0.25, -0.08, math.radians(4.0))
    flaser, rawlaser = _robot_logs(tmp_path, mounting)
    runner = CliRunner()
    profile_path = tmp_path / "robot.json"
    result = runner.invoke(app, ["calibrate", str(flaser), "--out", str(profile_path)])
    assert result.exit_code == 0, result.output
    profile = read_profile(profile_path)
    assert profile.mounting == pytest.approx(mounting, abs=1e-6)
    assert "x 0.250 m, y -0.080 m, theta 4.00 deg" in result.output

    def world_lines(log):
        out = tmp_path / f"{log.stem}.jsonl"
        args = ["run", str(log), "--out", str(out), "--frame", "world", "--overwrite"]
        result = runner.invoke(app, [*args, "--sensor-profile", str(profile_path)])
        assert result.exit_code == 0, result.output
        moved = "RAWLASER1 records carry the robot's pose; moved by the laser's mounting"
        assert (moved in result.output) == (log == rawlaser and profile.mounting is not None)
        rows = map(json.loads, out.open())
        return [[*s["start"], *s["end"], s["rho"], s["alpha"]] for r in rows for s in r["segments"]]

    from_flaser = world_lines(flaser)
    assert len(from_flaser) > 40
    np.testing.assert_allclose(world_lines(rawlaser), from_flaser, atol=1e-6)
    folder = tmp_path / "several"
    folder.mkdir()
    args = ["run", str(rawlaser), str(flaser), "--out", str(folder), "--format", "jsonl"]
    result = runner.invoke(app, [*args, "--frame", "world", "--sensor-profile", str(profile_path)])
    assert result.exit_code == 0, result.output
    rows = map(json.loads, (folder / f"{rawlaser.name}.jsonl").open())
    several = [[*s["start"], *s["end"], s["rho"], s["alpha"]] for r in rows for s in r["segments"]]
    np.testing.assert_allclose(several, from_flaser, atol=1e-6)
    profile = SensorProfile(**{**profile.__dict__, "mounting": None})
    profile.save(profile_path)
    assert not np.allclose(world_lines(rawlaser), from_flaser, atol=1e-3)


def test_a_mounting_is_only_taken_when_the_recorded_ones_agree():
    from scanlines.sensor.profile import estimate_mounting

    assert estimate_mounting([]) is None
    steady = [(0.1, 0.0, math.pi - 0.001), (0.1, 0.0, -math.pi + 0.001)] * 10
    assert estimate_mounting(steady) == pytest.approx((0.1, 0.0, math.pi), abs=2e-3)
    drifting = [(0.01 * k, 0.0, 0.0) for k in range(20)]
    assert estimate_mounting(drifting) is None
