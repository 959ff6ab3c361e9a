"""What ``help()`` shows of the entry points stays true: the methods ``extract`` names are
the registry's, and its example runs and gives what it shows."""

from __future__ import annotations

import doctest
import pydoc
import re

import scanlines
from scanlines.extractor import DEFAULT_METHOD


def help_text(obj: object) -> str:
    return pydoc.render_doc(obj, renderer=pydoc.plaintext)


def test_help_of_extract_names_every_registered_method() -> None:
    text = help_text(scanlines.extract)
    paragraph = text[text.index("    method:") : text.index("    preset:")]
    named = re.findall(r'``"(\w+)"``', paragraph)
    assert sorted(named) == sorted(scanlines.method_names())
    assert named[0] == DEFAULT_METHOD


def test_the_example_of_extract_runs_as_shown() -> None:
    finder = doctest.DocTestFinder(recurse=False)
    (test,) = finder.find(scanlines.extract, "extract", globs={})
    assert len(test.examples) >= 5
    runner = doctest.DocTestRunner(optionflags=doctest.NORMALIZE_WHITESPACE)
    runner.run(test)
    assert runner.summarize(verbose=False).failed == 0
