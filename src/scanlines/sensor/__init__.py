"""The sensor, measured from its own data (import the modules by name; importing this
package imports none of them)::

    profile     SensorProfile: range noise against range, beam geometry, dropouts,
                outliers, mixed pixels (estimate_profile, read_profile; scanlines calibrate)
    mounting    the laser's mounting on the robot, from the mountings a log records
    learned_noise
                the noise line an Extractor without a profile learns from its first scans
"""
