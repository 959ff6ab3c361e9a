"""Line maps: segments of every scan of a log fused into world-frame lines.

::

    from scanlines.io import open_log
    from scanlines.map import build_map

    with open_log("intel-corrected.log.gz") as reader:
        build = build_map(reader.enumerate())      # the log's poses, the default extractor
    lines = build.line_map.lines()                 # MapLines: rho, alpha, covariances, extent

Modules: ``fusion`` (association and fusion, :class:`LineMap`), ``poses`` (where each scan
stood), ``build`` (a log to a map), ``export`` (GeoJSON, SVG, DXF, JSON), ``holdout``
(the map scored on scans it did not see: ``scanlines eval --map``), ``align`` (a scan
pulled onto the map from its pose), ``tracking`` (odometry as the prior, each scan aligned:
``scanlines map --align``), ``filter`` (the filter of ``scanlines localize``: odometry as
the prior, its errors learnt, returns matched to map lines through a grid), ``tracked``
(tracked poses summarised and written),
``localize`` (a log tracked on a saved map: ``scanlines localize``) and ``relocalise``
(global localisation: pose hypotheses from a scan's segments, kept when scans agree).
"""

from scanlines.map.build import MapBuild, build_map
from scanlines.map.fusion import FusionSettings, LineMap, MapLines

__all__ = ["FusionSettings", "LineMap", "MapBuild", "MapLines", "build_map"]
