"""Fuzzing the log readers, the ``info`` / ``run`` commands and the map commands.

``seeds.py`` writes small valid logs of every format, ``mutate.py`` and
``mutate_npz.py`` damage them, ``plans.py`` says which damage each seed gets,
``channels.py`` reads an input four ways in worker processes and classifies
the outcomes, ``run.py`` drives a campaign (``python -m tests.fuzz.run
--help`` from the repository root), ``make_corpus.py`` builds ``corpus/``
(inputs that once failed) and ``test_fuzz.py`` runs both under pytest.
The map target: ``map_target.py`` (its seeds and plans), ``mutate_maps.py``
(pose and TUM mutators), ``map_channels.py`` (``map`` and ``eval --map``).
"""
