"""What a command prints while kernels compile: one announcement and one summary line per
command however many bursts it compiles in, nothing for short ones, nothing extra when it
fails. Driven by the compile events themselves, with no numba compile."""

from __future__ import annotations

import time

import pytest

from scanlines._compile_watch import compile_ended, compile_started
from scanlines.cli.common import CompileProgress, compile_progress


@pytest.fixture
def quick_banner(monkeypatch):
    monkeypatch.setattr(CompileProgress, "DELAY", 0.05)


def burst(kernels: int, seconds: float) -> None:
    for number in range(kernels):
        compile_started(f"kernel_{number}")
    time.sleep(seconds)
    for _ in range(kernels):
        compile_ended()


def test_three_long_bursts_are_announced_once_and_summed_once(quick_banner, capsys):
    with compile_progress():
        for _ in range(3):
            burst(2, 0.2)
    err = capsys.readouterr().err
    assert err.count("compiling kernels for first use") == 1
    assert err.count("scanlines: compiled 6 kernels in") == 1


def test_short_bursts_say_nothing(capsys, monkeypatch):
    monkeypatch.setattr(CompileProgress, "DELAY", 5.0)
    with compile_progress():
        burst(3, 0.0)
        burst(1, 0.0)
    assert capsys.readouterr().err == ""


def interrupted_while_compiling() -> None:
    with compile_progress():
        burst(1, 0.2)
        raise KeyboardInterrupt


def test_a_failing_command_prints_no_summary(quick_banner, capsys):
    with pytest.raises(KeyboardInterrupt):
        interrupted_while_compiling()
    err = capsys.readouterr().err
    assert err.count("compiling kernels for first use") == 1
    assert "scanlines: compiled" not in err
