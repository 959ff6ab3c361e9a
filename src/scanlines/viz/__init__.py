"""Figures: scans with their features, evaluation results, the reproduced paper figures.

The modules (import them by name; matplotlib is imported when a figure is drawn)::

    figures     pyplot() on a file backend, save()
    scans       plot_extraction(), plot_grid(): a scan and its features
    evaluation  detections over the truth, bars and worst scans of an evaluation
    reproduce   the figures of RESULTS.md (Fig. 13 redone, ground-truth bars)
"""

__all__ = ["evaluation", "figures", "reproduce", "scans"]
