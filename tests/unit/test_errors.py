"""Hints in error messages: close names, and names from user files kept on one line."""

import pytest

from rczone.errors import did_you_mean, printable


@pytest.mark.parametrize(
    ("name", "candidates", "hint"),
    [
        ("Rw ", ["Rw", "Cr"], "did you mean 'Rw'?"),
        ("cr", ["Rw", "Cr"], "did you mean 'Cr'?"),
        ("zzz", ["Rw", "Cr"], "known names: Cr, Rw"),
        ("zzz", [], "none are declared"),
        # a CSV header cell may hold a newline or a tab: the hint must stay one line
        ("time", [",Ti\n1300,4", "x\ty"], "known names: ,Ti\\n1300,4, x\\ty"),
        ("Ti", ["Ti\n"], "did you mean 'Ti\\n'?"),
    ],
)
def test_did_you_mean(name, candidates, hint):
    assert did_you_mean(name, candidates) == hint
    assert "\n" not in hint


def test_printable_escapes_only_what_cannot_be_printed():
    assert printable("µ-Ti 1") == "µ-Ti 1"  # printable non-ASCII stays as written
    assert printable("a\x00b\r") == "a\\x00b\\r"
