"""Fuzzing the log readers, the ``info`` / ``run`` commands, the map commands, the files
that set things and the ROS 2 node.

Six targets, chosen by ``run.py --targets`` (any of ``logs maps params profiles linemaps
dds``; default all but ``dds``). The log target: ``seeds.py`` writes small valid logs of
every format, ``mutate.py`` and ``mutate_npz.py`` damage them, ``plans.py`` says which
damage each seed gets, ``channels.py`` reads an input four ways in worker processes and
classifies the outcomes. The map target: ``map_target.py`` (its seeds and plans),
``mutate_maps.py`` (pose and TUM mutators), ``map_channels.py`` (``map`` and ``eval
--map``). The settings-file targets (parameters files and configurations, sensor profiles,
the line maps ``localize`` reads): ``file_target.py`` (seeds and plans),
``mutate_files.py`` (YAML, TOML and JSON mutators: alias bombs, deep nesting, huge
integers, booleans, maps whose lines disagree with their ends), ``file_channels.py``. The
DDS target: ``mutate_cdr.py`` damages a ``sensor_msgs/LaserScan`` sample and
``dds_target.py`` sends each to one running ``scanlines ros2`` node over loopback (opt-in:
``--targets dds``). ``run.py`` drives a campaign (``python -m tests.fuzz.run --help`` from
the repository root); ``binaries.py`` ends it if a shared object it runs on is rewritten
meanwhile. ``make_corpus.py`` builds ``corpus/`` (inputs that once failed; ``corpus_dds/``
holds the DDS samples) and ``test_fuzz.py`` runs both under pytest.
"""
