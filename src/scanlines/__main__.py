"""``python -m scanlines`` runs the command-line tool."""

from scanlines.cli import main

main()
