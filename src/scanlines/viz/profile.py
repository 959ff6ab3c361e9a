"""The noise curve of a :class:`~scanlines.sensor.profile.SensorProfile`."""

from __future__ import annotations

from typing import Any

import numpy as np

from scanlines.sensor.profile import SensorProfile
from scanlines.viz.figures import pyplot

__all__ = ["plot_noise_curve"]


def plot_noise_curve(profile: SensorProfile, title: str | None = None) -> Any:
    """Measured range noise per range bin (with its bootstrap error) and the noise line."""
    plt = pyplot()
    figure, axes = plt.subplots(figsize=(6.4, 4.0))
    bins = profile.noise_bins
    r = np.array([b.range for b in bins])
    sigma = 1000 * np.array([b.sigma for b in bins])
    error = 1000 * np.array([b.error for b in bins])
    axes.errorbar(r, sigma, yerr=error, fmt="o", capsize=3, label="measured (bin median range)")
    span = np.linspace(0.0, max(float(r.max(initial=1.0)) * 1.1, 1.0), 50)
    axes.plot(span, 1000 * profile.sigma_at(span), "-", label="noise line used")
    axes.set_xlabel("range (m)")
    axes.set_ylabel("range noise sigma (mm)")
    axes.set_xlim(left=0.0)
    axes.set_ylim(bottom=0.0)
    axes.grid(alpha=0.3)
    axes.legend(loc="upper left")
    axes.set_title(title or f"sensor profile: {profile.source or 'log'} ({profile.scans} scans)")
    return figure
