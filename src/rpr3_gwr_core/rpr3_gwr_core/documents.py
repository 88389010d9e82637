"""YAML documents read from files, whatever the files hold.

Scene files (:func:`~rpr3_gwr_core.io.scene_file.load_scene`) and mechanism files
(:func:`~rpr3_gwr_core.io.mechanism_file.load_mechanism_file`) are read by
:func:`read_document`: at most :data:`MAX_DOCUMENT_BYTES` bytes of UTF-8
text (a UTF-8 byte-order mark allowed), parsed with PyYAML's safe loader.
Every other content, bytes that are not UTF-8 (UTF-16, Latin-1, binary),
YAML nested too deeply for the parser, an integer of thousands of digits, a
malformed timestamp or a list or mapping repeated by an alias (``*name``:
a few lines of them make a structure of billions of items, or one that
contains itself), fails with one :class:`InvalidInputError` naming the
file.

Numbers follow YAML 1.2 (and JSON): ``1e300`` and ``1.5e-3`` are numbers.
PyYAML reads YAML 1.1, where a number with an exponent needs a dot and a
signed exponent (``1.0e+300``) and ``1e300`` is the string ``"1e300"``;
here it is the number a user means.  What a value may be (its range, its
type) is for the reader of the document to check.
"""

import functools
import re

from .exceptions import InvalidInputError

__all__ = ["read_document", "MAX_DOCUMENT_BYTES"]

MAX_DOCUMENT_BYTES = 256 * 1024
"""Largest file :func:`read_document` reads [bytes] (256 KiB): a scene as
large as :mod:`~rpr3_gwr_core.world.scene` allows, every coordinate with
all its digits, takes about 40 KB, a mechanism file a few.  PyYAML's
pure-Python parser, the one that stops at a depth it cannot follow (its C
parser would crash), takes one to three seconds over 256 KiB."""

# YAML 1.2's numbers with an exponent that YAML 1.1 reads as strings: no
# dot, or an exponent without its sign ("1e300", "2.5e3", ".5e-3").
_EXPONENT_FLOAT = re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9][0-9_]*)"
                             r"[eE][-+]?[0-9]+$")


def read_document(path, what):
    """The YAML document of a file.

    Parameters
    ----------
    path : str or os.PathLike
    what : str
        What the file holds, as messages name it (``"scene"``).

    Returns
    -------
    object
        The parsed document: None for an empty file, else a mapping, a
        list or a scalar.

    Raises
    ------
    InvalidInputError
        If the file is larger than :data:`MAX_DOCUMENT_BYTES`, is not UTF-8
        text, is not YAML or repeats a list or mapping (its message one
        line, naming the file).
    OSError
        If it cannot be opened or read.
    """
    with open(path, "rb") as stream:
        # One byte past the limit tells a file over it without reading it all.
        data = stream.read(MAX_DOCUMENT_BYTES + 1)
    if len(data) > MAX_DOCUMENT_BYTES:
        raise InvalidInputError(f"{what} {path} is larger than the limit of "
                                f"{MAX_DOCUMENT_BYTES:,} bytes")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InvalidInputError(f"{what} {path} is not UTF-8 text: byte "
                                f"0x{data[exc.start]:02x} at offset {exc.start}") from None
    document = _parsed(text, f"{what} {path}")
    _refuse_repeats(document, f"{what} {path}")
    return document


def _refuse_repeats(document, where):
    """Refuse a list or mapping met twice: an alias of one."""
    seen, pending = set(), [document]
    while pending:  # a loop, not a recursion: a document may nest deeply
        value = pending.pop()
        if isinstance(value, (list, dict)):
            if id(value) in seen:
                raise InvalidInputError(f"{where} repeats a list or mapping by an alias "
                                        "(*name): write each one out")
            seen.add(id(value))
            pending += value.values() if isinstance(value, dict) else value


def _parsed(text, where):
    """The YAML document of ``text``, its errors one line naming ``where``."""
    import yaml

    try:
        return yaml.load(text, Loader=_loader())
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark
        at = "" if mark is None else f" (line {mark.line + 1}, column {mark.column + 1})"
        raise InvalidInputError(f"{where} is not YAML: {_one_line(exc.problem or exc)}{at}") \
            from None
    except yaml.YAMLError as exc:
        raise InvalidInputError(f"{where} is not YAML: {_one_line(exc)}") from None
    except RecursionError:
        raise InvalidInputError(f"{where} is nested too deeply to be read") from None
    except ValueError as exc:
        # PyYAML's constructors: an integer over Python's 4,300 digits of
        # conversion, a date such as 2001-13-01.
        raise InvalidInputError(f"{where} holds a value that cannot be read: "
                                f"{_one_line(exc).split(';')[0]}") from None


@functools.cache
def _loader():
    """PyYAML's safe loader, with YAML 1.2's numbers with an exponent."""
    import yaml

    class Loader(yaml.SafeLoader):
        pass

    Loader.add_implicit_resolver("tag:yaml.org,2002:float", _EXPONENT_FLOAT,
                                 list("-+0123456789."))
    return Loader


def _one_line(message):
    return " ".join(str(message).split())
