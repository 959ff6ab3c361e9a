"""Fuzzing the log readers, the ``info`` / ``run`` commands and the ROS 2 node.

``seeds.py`` writes small valid logs of every format, ``mutate.py`` and
``mutate_npz.py`` damage them, ``plans.py`` says which damage each seed gets,
``channels.py`` reads an input four ways in worker processes and classifies
the outcomes, ``run.py`` drives a campaign (``python -m tests.fuzz.run
--help`` from the repository root), ``make_corpus.py`` builds ``corpus/``
(inputs that once failed) and ``test_fuzz.py`` runs both under pytest. The DDS
target: ``mutate_cdr.py`` damages a ``sensor_msgs/LaserScan`` sample and
``dds_target.py`` sends each to one running ``scanlines ros2`` node over loopback
(``--targets dds``).
"""
