"""``docs/PERFORMANCE.md``: ``scanlines bench`` run and written down as the repository's page."""
