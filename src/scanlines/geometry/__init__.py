"""Planar geometry shared by the readers, the writers, the maps and the evaluation
(import the modules by name; importing this package imports none of them)::

    poses          Pose (x, y, theta): compose, invert, relative_pose
    transform      points and extracted features moved into the world frame by a pose
    registration   a point-to-line ICP (scan to scan) and the one Gauss-Newton
                   point-to-line step it shares with the map's alignment
"""
