"""What ``scanlines bench`` times and how often: :class:`BenchConfig`."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

from scanlines import Extractor, ParameterError, method_names

__all__ = ["DEFAULT_BEAMS", "MAX_BEAMS", "QUICK_BEAMS", "SAMPLE_NAMES", "BenchConfig"]

SAMPLE_NAMES = ("intel", "freiburg")
DEFAULT_BEAMS = (100, 300, 1000, 3000, 10000)
QUICK_BEAMS = (100, 1000)
MAX_BEAMS = 100_000


@dataclass(frozen=True)
class BenchConfig:
    """What to time and how often.

    Parameters
    ----------
    methods:
        Method names; empty: every registered method, in registry order.
    sensors:
        Sensor presets for the simulated datasets; empty: all presets.
    real_scans:
        Scans taken from the start of each real excerpt.
    sim_scans:
        Simulated scans (one scene each) per sensor preset.
    repeats:
        Timed passes over each dataset.
    beam_counts:
        Beam counts of the scaling run (empty: no scaling run).
    scaling_scans:
        Scans (noise draws of the one scene) per beam count.
    seed:
        Base seed of the simulated scenes and noise.
    batch:
        Time :meth:`Extractor.batch` against the loop on the real excerpts.
    profile:
        Run :mod:`cProfile` on the default extractor over the intel excerpt.
    profile_scans:
        Intel scans profiled; ``None``: the whole excerpt.
    profile_top:
        Functions listed by the profile.
    quick:
        Recorded in the output (set by :meth:`quick_config`).
    """

    methods: tuple[str, ...] = ()
    sensors: tuple[str, ...] = ()
    real_scans: int = 100
    sim_scans: int = 50
    repeats: int = 3
    beam_counts: tuple[int, ...] = DEFAULT_BEAMS
    scaling_scans: int = 10
    seed: int = 0
    batch: bool = True
    profile: bool = False
    profile_scans: int | None = None
    profile_top: int = 15
    pipeline: bool = True
    pipeline_scans: int | None = None
    jobs: int = 1
    cold_start: bool = True
    quick: bool = False

    @classmethod
    def quick_config(cls, **changes: Any) -> BenchConfig:
        """A tiny run for CI: few scans, one repeat, beam counts 100 and 1000."""
        base = cls(
            real_scans=5,
            sim_scans=3,
            repeats=1,
            beam_counts=QUICK_BEAMS,
            scaling_scans=2,
            profile_scans=5,
            pipeline_scans=20,
            cold_start=False,
            quick=True,
        )
        return dataclasses.replace(base, **changes)

    def validated(self) -> BenchConfig:
        """This configuration with methods and sensors resolved and checked.

        Raises
        ------
        ParameterError
            For an unknown method or sensor preset, or a count out of range.
        """
        from scanlines.sim import SENSORS, get_sensor

        chosen = tuple(dict.fromkeys(self.methods)) or method_names()
        for name in chosen:
            Extractor(name)  # raises ParameterError naming the valid methods
        sensors = tuple(dict.fromkeys(self.sensors)) or tuple(SENSORS)
        for name in sensors:
            get_sensor(name)
        for label, value, low in (
            ("real scans", self.real_scans, 1),
            ("simulated scans", self.sim_scans, 1),
            ("repeats", self.repeats, 1),
            ("scaling scans", self.scaling_scans, 1),
            ("profile functions", self.profile_top, 1),
            ("jobs", self.jobs, 1),
        ):
            if value < low:
                raise ParameterError(f"{label} must be >= {low}, got {value}")
        if self.profile_scans is not None and self.profile_scans < 1:
            raise ParameterError(f"profile scans must be >= 1, got {self.profile_scans}")
        beams = tuple(sorted(set(self.beam_counts)))
        for n in beams:
            if not 2 <= n <= MAX_BEAMS:
                raise ParameterError(f"beam counts must be in 2..{MAX_BEAMS}, got {n}")
        return dataclasses.replace(self, methods=chosen, sensors=sensors, beam_counts=beams)

    def to_dict(self) -> dict[str, Any]:
        """The settings, as the JSON output records them."""
        return {
            "methods": list(self.methods),
            "sensors": list(self.sensors),
            "real_scans": self.real_scans,
            "sim_scans": self.sim_scans,
            "repeats": self.repeats,
            "beam_counts": list(self.beam_counts),
            "scaling_scans": self.scaling_scans,
            "seed": self.seed,
            "batch": self.batch,
            "profile": self.profile,
            "profile_scans": self.profile_scans,
            "pipeline": self.pipeline,
            "pipeline_scans": self.pipeline_scans,
            "jobs": self.jobs,
            "cold_start": self.cold_start,
            "quick": self.quick,
        }


# --------------------------------------------------------------------------- datasets
