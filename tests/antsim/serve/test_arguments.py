"""Request arguments of antsim serve (antsim.serve.arguments): each error names the argument."""

from __future__ import annotations

import pytest

from antsim.serve.arguments import (
    ArgumentError,
    at_most,
    integer,
    number,
    numbers,
    quoted,
    within,
)


def test_numbers_are_read_as_any_float_text():
    assert number((b"1e2", b"-0.5"), 1, "SECONDS") == -0.5
    assert number((b"1e2",), 0, "SECONDS") == 100.0
    assert numbers((b"1", b"2.5", b"-3e-1")) == [1.0, 2.5, -0.3]
    assert integer((b"7",), 0, "N") == 7


@pytest.mark.parametrize("call, message", [
    (lambda: number((), 0, "SECONDS"), "argument 1 (SECONDS) is missing"),
    (lambda: number((b"abc",), 0, "SECONDS"), "argument 1 (SECONDS) 'abc' is not a number"),
    (lambda: number((b"0", b"nan"), 1, "AZ"), "argument 2 (AZ) 'nan' is not a finite number"),
    (lambda: within((b"95",), 0, "EL", 0.0, 90.0, "deg"),
     "argument 1 (EL) '95': must lie within 0..90 deg"),
    (lambda: within((b"-1",), 0, "T", 0.0, 10.0), "argument 1 (T) '-1': must lie within 0..10"),
    (lambda: integer((b"1.5",), 0, "N"), "argument 1 (N) '1.5' is not an integer"),
    (lambda: integer((), 0, "N"), "argument 1 (N) is missing"),
    (lambda: at_most((b"a", b"b", b"c"), 2, "?x A B"), "too many arguments (3): usage ?x A B"),
    (lambda: numbers((b"1", b"x")), "argument 2 'x' is not a number"),
])
def test_a_bad_argument_gets_a_message_naming_it(call, message):
    with pytest.raises(ArgumentError) as err:
        call()
    assert str(err.value) == message


def test_bytes_that_are_not_utf8_are_quoted_without_failing():
    assert quoted(b"\xff1") == repr("\ufffd1")
    with pytest.raises(ArgumentError, match="is not a number"):
        number((b"\xff1",), 0, "X")
    assert within((b"90",), 0, "EL", 0.0, 90.0) == 90.0  # the limits are inclusive
    at_most((b"a",), 1, "?x A")  # n arguments are allowed
