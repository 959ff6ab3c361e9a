"""Sensor presets: beam geometry, range limits and noise of real 2D laser scanners.

Bearings follow REP 103 (x forward, y left, counter-clockwise positive), as in
:class:`scanlines.Scan`. The numbers and the choices made where a datasheet leaves
room:

``"lms_1deg"`` -- SICK LMS 200/291 at 1 deg, the sensor of the Intel Research Lab
    CARMEN log: 180 beams from -90 deg to +89 deg (the log's layout), 80 m maximum
    range, ranges stored with 1 cm resolution. Datasheet: systematic error
    +-15 mm, statistical error about 5 mm (1 sigma) in the 8/80 m modes. Chosen:
    Gaussian sigma = 10 mm (the typical 5 mm doubled for dark, shiny or oblique
    surfaces, which the simulator does not model otherwise), a per-scan bias drawn
    from U(-15 mm, +15 mm), 1 cm quantisation.
``"lms_05deg"`` -- the same scanner at 0.5 deg, as in the Freiburg building 079
    log: 360 beams from -90 deg to +89.5 deg; same noise and range.
``"tim571"`` -- SICK TiM571, the paper's sensor: 481 beams at 1/3 deg (the
    datasheet's 0.33 deg; 480 steps of exactly 1/3 deg span the 160 deg field), range
    0.05-25 m, statistical error 20 mm (1 sigma), systematic error up to +-60 mm
    (drawn once per scan from U(-60 mm, +60 mm)), 1 mm resolution. The paper
    measures bearings from 10 deg to 170 deg in a frame whose 90 deg points forward;
    here ``angle_min = -80 deg`` so that the beams span the front symmetrically
    (paper bearing = our bearing + 90 deg).
``"urg04lx"`` -- Hokuyo URG-04LX: 683 beams at 360/1024 deg (1024 steps per turn),
    centred on the front beam: ``angle_min = -341 * 2 pi / 1024`` (-119.88 deg) to
    +119.88 deg, i.e. the 240 deg field; range 0.02-5.6 m; accuracy +-30 mm up to
    1 m, +-3 % of the range beyond; 1 mm resolution. Chosen: the accuracy bound split into one third
    statistical 1 sigma (``max(10 mm, 1 % r)``) and two thirds per-scan bias
    (``u * max(20 mm, 2 % r)``, ``u ~ U(-1, 1)``), so that 1 sigma plus the bias never
    exceeds the bound.

Dropouts, outliers and mixed pixels are not in datasheets: every preset uses 1 %
dropouts and 1 % outliers; mixed pixels appear at half of the depth discontinuities
(40 % for the TiM571, which resolves multiple echoes better). Override any of it with
:func:`dataclasses.replace` on the preset or its ``noise``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Any

import numpy as np

from scanlines.scan import is_full_circle
from scanlines.sim.noise import NoiseModel

__all__ = ["SENSORS", "SensorSpec"]


@dataclass(frozen=True)
class SensorSpec:
    """Beam layout, range limits and noise of one 2D laser scanner.

    Parameters
    ----------
    name:
        Preset name (or any label).
    n_beams:
        Number of beams per scan.
    angle_min:
        Bearing of beam 0 in radians, sensor frame.
    angle_increment:
        Bearing step in radians (negative for clockwise scanners).
    range_min, range_max:
        Valid range interval in metres; measurements outside are no return.
    noise:
        The default :class:`NoiseModel`.
    description:
        Where the numbers come from.
    """

    name: str
    n_beams: int
    angle_min: float
    angle_increment: float
    range_min: float
    range_max: float
    noise: NoiseModel = field(default_factory=NoiseModel)
    description: str = ""

    def __post_init__(self) -> None:
        if self.n_beams < 1:
            raise ValueError(f"n_beams must be >= 1, got {self.n_beams}")
        if self.angle_increment == 0.0 or not math.isfinite(self.angle_increment):
            raise ValueError(
                f"angle_increment must be finite and non-zero, got {self.angle_increment}"
            )
        if not 0.0 <= self.range_min < self.range_max:
            raise ValueError(
                f"need 0 <= range_min < range_max, got {self.range_min}, {self.range_max}"
            )

    @property
    def angles(self) -> np.ndarray:
        """Bearing of every beam in radians (sensor frame)."""
        return self.angle_min + self.angle_increment * np.arange(self.n_beams, dtype=np.float64)

    @property
    def angle_max(self) -> float:
        """Bearing of the last beam."""
        return self.angle_min + self.angle_increment * (self.n_beams - 1)

    @property
    def full_circle(self) -> bool:
        """True when the beams close the circle (:func:`scanlines.scan.is_full_circle`)."""
        return is_full_circle(self.n_beams, self.angle_increment)

    def with_noise(self, noise: NoiseModel | None = None, **changes: Any) -> SensorSpec:
        """This sensor with another noise model, or with some noise fields changed."""
        base = self.noise if noise is None else noise
        return replace(self, noise=replace(base, **changes))


_LMS_NOISE = NoiseModel(
    sigma=0.010,
    bias=0.015,
    quantum=0.01,
    dropout_prob=0.01,
    outlier_prob=0.01,
    mixed_pixel_prob=0.5,
)

_PRESETS = (
    SensorSpec(
        name="lms_1deg",
        n_beams=180,
        angle_min=math.radians(-90.0),
        angle_increment=math.radians(1.0),
        range_min=0.0,
        range_max=80.0,
        noise=_LMS_NOISE,
        description="SICK LMS 180 deg at 1 deg as in the Intel Research Lab log (-90..+89 deg)",
    ),
    SensorSpec(
        name="lms_05deg",
        n_beams=360,
        angle_min=math.radians(-90.0),
        angle_increment=math.radians(0.5),
        range_min=0.0,
        range_max=80.0,
        noise=_LMS_NOISE,
        description="SICK LMS 180 deg at 0.5 deg as in the Freiburg 079 log (-90..+89.5 deg)",
    ),
    SensorSpec(
        name="tim571",
        n_beams=481,
        angle_min=math.radians(-80.0),
        angle_increment=math.radians(1.0 / 3.0),
        range_min=0.05,
        range_max=25.0,
        noise=NoiseModel(
            sigma=0.020,
            bias=0.060,
            quantum=0.001,
            dropout_prob=0.01,
            outlier_prob=0.01,
            mixed_pixel_prob=0.4,
        ),
        description="SICK TiM571, 160 deg at 1/3 deg (paper's 10..170 deg = our -80..+80 deg)",
    ),
    SensorSpec(
        name="urg04lx",
        n_beams=683,
        angle_min=-341 * 2.0 * math.pi / 1024,
        angle_increment=2.0 * math.pi / 1024,
        range_min=0.02,
        range_max=5.6,
        noise=NoiseModel(
            sigma=0.010,
            sigma_rel=0.01,
            bias=0.020,
            bias_rel=0.02,
            quantum=0.001,
            dropout_prob=0.01,
            outlier_prob=0.01,
            outlier_far=2.0,
            mixed_pixel_prob=0.5,
        ),
        description="Hokuyo URG-04LX, 240 deg at 360/1024 deg, 0.02-5.6 m",
    ),
)

SENSORS: MappingProxyType[str, SensorSpec] = MappingProxyType({s.name: s for s in _PRESETS})
"""The sensor presets by name (read-only)."""
