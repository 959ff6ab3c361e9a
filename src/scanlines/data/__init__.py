"""Small real laser logs shipped with scanlines, for examples, tests and demos.

================  =====================================================  =======
name              what                                                   scans
================  =====================================================  =======
``"intel"``       Intel Research Lab (Seattle), SICK LMS, 180 beams at   300
                  1 deg, raw odometry poses; CARMEN ``FLASER``, gzip
``"freiburg"``    University of Freiburg building 079, SICK LMS, 360     300
                  beams at 0.5 deg, with the log's ``PARAM`` and ``ODOM``
                  lines; CARMEN, gzip
``"urg"``         Paris Mines Tech robot, Hokuyo URG-04LX, 683 beams at  150
                  0.35 deg, more than half without a return; CoreSLAM
                  ``.dat``, gzip
================  =====================================================  =======

All are consecutive excerpts with corridors, doors and room corners; see
``PROVENANCE.md`` in this package for sources, citations, licences and how
they were cut. Read them with :func:`scanlines.io.open_log`::

    from scanlines.data import sample
    from scanlines.io import open_log
    scans = list(open_log(sample("intel")))
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["SAMPLES", "provenance", "sample"]

_HERE = Path(__file__).resolve().parent

#: Sample name -> file name in this package.
SAMPLES = {
    "intel": "intel_excerpt.clf.gz",
    "freiburg": "fr079_excerpt.log.gz",
    "urg": "urg_excerpt.dat.gz",
}


def sample(name: str) -> Path:
    """Path of a shipped sample log.

    Parameters
    ----------
    name:
        ``"intel"``, ``"freiburg"`` or ``"urg"``.

    Raises
    ------
    ValueError
        For any other name; the message lists the valid ones.
    """
    if name not in SAMPLES:
        valid = ", ".join(repr(n) for n in SAMPLES)
        raise ValueError(f"unknown sample {name!r}; samples: {valid}")
    return _HERE / SAMPLES[name]


def provenance() -> str:
    """The text of ``PROVENANCE.md``: sources, citations and licences of the samples."""
    return (_HERE / "PROVENANCE.md").read_text(encoding="utf-8")
