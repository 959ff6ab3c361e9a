"""A command that writes without being told where writes into the current folder (or
its ``--out``), never beside an input: a shipped sample lives inside the installed
package."""

from __future__ import annotations

import shutil

from cli_helpers import scanlines
from scanlines.data import sample


def test_calibrate_writes_its_profile_into_the_current_folder(tmp_path) -> None:
    logs, work = tmp_path / "logs", tmp_path / "work"
    logs.mkdir()
    work.mkdir()
    log = shutil.copy(sample("intel"), logs)
    out = scanlines("calibrate", log, "--scans", "60", cwd=work)
    assert out.returncode == 0, out.stderr
    assert "wrote intel_excerpt.profile.json" in out.stdout
    assert (work / "intel_excerpt.profile.json").is_file()
    assert sorted(p.name for p in logs.iterdir()) == ["intel_excerpt.clf.gz"]


def test_calibrate_of_a_shipped_sample_leaves_the_package_alone(tmp_path) -> None:
    package = sample("intel").parent
    before = sorted(p.name for p in package.iterdir())
    out = scanlines("calibrate", sample("freiburg"), "--scans", "40", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "fr079_excerpt.profile.json").is_file()
    assert sorted(p.name for p in package.iterdir()) == before


def test_plot_without_output_draws_into_the_current_folder(tmp_path) -> None:
    out = scanlines("plot", sample("intel"), "--scan", "3", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "scanlines-plot.png").is_file()
