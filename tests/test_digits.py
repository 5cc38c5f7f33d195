"""Printed values carry the digits their uncertainty supports (feloop/digits.py)."""
from __future__ import annotations

from feloop.digits import decimals, fmt, fmt_interval


def test_a_fitted_value_to_two_digits_of_its_standard_error():
    # the lap's chi: -0.637464 in -0.679426 .. -0.595502 (95 %), sd 0.021
    assert fmt_interval(-0.637464, -0.679426, -0.595502) == ("-0.637", "-0.679", "-0.596")
    # the kernels' two optima print alike
    assert fmt_interval(-0.6374633, -0.679425, -0.595502)[0] == "-0.637"
    assert fmt_interval(0.000997547, 0.000996099, 0.000998995)[0] == "0.00099755"
    assert fmt_interval(6.819e7, 6.5e7, 7.1e7) == ("6.82e+07", "6.50e+07", "7.10e+07")
    assert fmt(1234.5, 127.0) == "1230"
    assert decimals(0.021) == 3 and decimals(0.0) is None


def test_without_an_interval_the_callers_format_stays():
    assert fmt_interval(9.453291, None, None, fallback=".7g") == ("9.453291", "open", "open")
    assert fmt(None, 0.1) == "open"
    # one open end: its distance from the value stands for the half-width
    assert fmt_interval(0.5, None, 0.7) == ("0.50", "open", "0.70")


def test_a_shift_below_the_noise_prints_as_zero():
    assert fmt(3.91e-07, 3.6e-4, ".3g", 1) == "0.0000"
    assert fmt(-0.00118, 0.074, ".3g", 1) == "0.00"        # no "-0.00"
    assert fmt(0.0123, 3.6e-4, ".3g", 1) == "0.0123"
