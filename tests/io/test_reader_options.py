"""ReaderOptions: the one type of every reader's options."""

import math

import pytest

from scanlines.data import sample
from scanlines.errors import ParameterError
from scanlines.io import READERS, ReaderOptions, open_log, reader_option_names


def test_its_fields_are_every_readers_options_and_no_other():
    taken = {name for format_name in READERS for name in reader_option_names(format_name)}
    assert set(ReaderOptions.names()) == taken


def test_only_the_options_set_are_given():
    options = ReaderOptions(fov=math.pi, on_error="skip")
    assert options.given() == {"fov": math.pi, "on_error": "skip"}
    assert options.but(fov=None).given() == {"on_error": "skip"}
    assert ReaderOptions.of(None) == ReaderOptions()
    assert ReaderOptions.of({"topic": "/scan"}) == ReaderOptions(topic="/scan")


def test_an_unknown_name_is_refused_with_the_valid_ones():
    with pytest.raises(ParameterError, match=r"unknown reader option\(s\) fvo; options: message"):
        ReaderOptions.of({"fvo": 3.0})


def test_open_log_takes_them_and_keywords_win():
    path = sample("intel")
    with open_log(path, options=ReaderOptions(max_beams=10)) as reader:
        assert reader.max_beams == 10
    with open_log(path, options=ReaderOptions(max_beams=10), max_beams=500) as reader:
        assert reader.max_beams == 500


def test_an_option_the_logs_reader_does_not_take_names_the_file():
    with pytest.raises(ParameterError, match=r"intel.*option\(s\) topic do not apply to carmen"):
        open_log(sample("intel"), options=ReaderOptions(topic="/scan"))
