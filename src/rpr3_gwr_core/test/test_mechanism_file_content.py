"""Mechanism files of any content: one ``InvalidInputError`` whatever the
file holds (bytes that are not UTF-8, YAML too deep, numbers beyond any
float, booleans for numbers, a file too large), ``OSError`` when it cannot
be read, and the YAML 1.2 numbers a user means."""

import copy
import pathlib
import re
import warnings

import pytest
import yaml
from hypothesis import given, settings, strategies as st

from rpr3_gwr_core.documents import MAX_DOCUMENT_BYTES
from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.io.mechanism_file import (MAX_MAGNITUDE, load_mechanism_file,
                                              mechanism_file_from_dict)

CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config"
FILES = ("paper_3rpr", "five_bar", "three_prr", "three_rrr")
DOCUMENTS = {name: yaml.safe_load((CONFIG / f"{name}.yaml").read_text()) for name in FILES}
PAPER = (CONFIG / "paper_3rpr.yaml").read_text()

_HOSTILE = {
    "random bytes": bytes(range(256)) * 4,
    "utf-16": PAPER.encode("utf-16"),
    "latin-1": (PAPER + "# caf\xe9\n").encode("latin-1"),
    "nested": b"mechanism: " + b"[" * 50_000 + b"]" * 50_000,
    "nested blocks": b"- " * 50_000 + b"x\n",
    "400 digits": PAPER.replace("d1: 17.04", "d1: " + "9" * 400).encode(),
    "5000 digits": PAPER.replace("d1: 17.04", "d1: " + "9" * 5000).encode(),
    "huge coordinates": PAPER.replace("a2: [15.91, 0.0]", "a2: [1.0e+200, 1.0e+200]").encode(),
    "1e300 step": PAPER.replace("step: 0.125", "step: 1e300").encode(),
    "a boolean length": PAPER.replace("d1: 17.04", "d1: true").encode(),
    "a boolean coordinate": PAPER.replace("a3: [0.0, 10.0]", "a3: [true, 10.0]").encode(),
    "a boolean range": PAPER.replace("min: 0.0", "min: false").encode(),
    "legs in two layers": (PAPER + "bodies: {leg_layers: [1, 1]}\n").encode(),
    "tab": b"mechanism:\n\t- 1\n",
    "itself": PAPER.replace("a1: [0.0, 0.0]", "a1: &a [*a, 0.0]").encode(),
    "aliases": "\n".join(["b0: &b0 [1, 1, 1, 1, 1, 1, 1, 1, 1]"] + [
        f"b{k}: &b{k} [{', '.join([f'*b{k - 1}'] * 9)}]" for k in range(1, 10)]).encode()
    + b"\n" + PAPER.replace("a1: [0.0, 0.0]", "a1: *b9").encode(),
    "too large": PAPER.encode() + b"#" * MAX_DOCUMENT_BYTES,
}


@pytest.mark.parametrize("name", sorted(_HOSTILE))
def test_a_mechanism_file_of_any_content_fails_with_one_line(name, tmp_path):
    path = tmp_path / "robot.yaml"
    path.write_bytes(_HOSTILE[name])
    with pytest.raises(InvalidInputError) as error:
        load_mechanism_file(path)
    message = str(error.value)
    assert "\n" not in message and len(message) < 400 and str(path) in message


def test_a_file_that_cannot_be_read_raises_os_error(tmp_path):
    with pytest.raises(FileNotFoundError):
        load_mechanism_file(tmp_path / "missing.yaml")
    with pytest.raises(IsADirectoryError):
        load_mechanism_file(tmp_path)


def test_a_number_with_an_exponent_is_the_number_it_writes(tmp_path):
    # YAML 1.1 (PyYAML) reads 1.25e-1 and 5e1 as strings.
    path = tmp_path / "robot.yaml"
    path.write_text(PAPER.replace("step: 0.125", "step: 1.25e-1").replace("max: 50.0",
                                                                           "max: 5e1"))
    assert load_mechanism_file(path) == load_mechanism_file(CONFIG / "paper_3rpr.yaml")


def test_the_bound_of_a_number_is_named():
    document = copy.deepcopy(DOCUMENTS["paper_3rpr"])
    document["joints"][1]["max"] = 10 ** 400
    bound = re.escape(f"out of range: a mechanism file's numbers are at most {MAX_MAGNITUDE:g}")
    with pytest.raises(InvalidInputError, match=r"'joints\[1\].max' = 1000.* is " + bound):
        mechanism_file_from_dict(document)


def _places(document, where=()):
    """Every key and item of a document, as paths."""
    items = document.items() if isinstance(document, dict) else (
        enumerate(document) if isinstance(document, list) else ())
    for key, value in items:
        yield where + (key,)
        yield from _places(value, where + (key,))


_VALUES = st.one_of(
    st.sampled_from([True, False, None, "1e300", "", [], {}, 0, -1, 10 ** 400, -10 ** 400,
                     1e200, -1e308, 5e-324, float("nan"), float("inf"), MAX_MAGNITUDE,
                     2 * MAX_MAGNITUDE, [1e200, 1e200], [True, 0], {"kind": "3-RPR"}]),
    st.floats(allow_nan=True, allow_infinity=True), st.integers(), st.text(max_size=5))


@settings(max_examples=300, deadline=None, database=None)
@given(data=st.data())
def test_a_changed_document_is_a_mechanism_file_or_one_invalid_input_error(data):
    name = data.draw(st.sampled_from(FILES))
    document = copy.deepcopy(DOCUMENTS[name])
    for _ in range(data.draw(st.integers(1, 3))):
        place = data.draw(st.sampled_from(list(_places(document))))
        parent = document
        for key in place[:-1]:
            parent = parent[key]
        parent[place[-1]] = copy.deepcopy(data.draw(_VALUES))
    with warnings.catch_warnings():
        # An overflow or invalid value on the way is a failure, as in the tool.
        warnings.simplefilter("error", RuntimeWarning)
        try:
            mechanism_file_from_dict(document)
        except InvalidInputError as exc:
            assert "\n" not in str(exc)
