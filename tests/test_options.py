"""The option validators every solver shares (evoik_pin.solvers.options)."""

import numpy as np
import pytest

from evoik_pin.errors import OptionError
from evoik_pin.solvers.options import (
    check_callback,
    check_choice,
    check_fraction,
    check_int,
    check_nonnegative,
    check_nonnegative_vector,
    check_number,
    check_positive,
)


@pytest.mark.parametrize("value", [1, 7, np.int64(3), np.int32(1), 10**12])
def test_check_int_accepts_integers_at_or_above_the_minimum(value):
    got = check_int("population", value)
    assert got == int(value) and type(got) is int


@pytest.mark.parametrize("value", [0, -3, 2.0, 1.5, "4", None, True, np.float64(3.0)])
def test_check_int_rejects_the_rest_naming_option_and_range(value):
    with pytest.raises(OptionError, match=r"population must be an integer >= 1, got"):
        check_int("population", value)


def test_check_int_with_minimum_and_maximum():
    assert check_int("bits", 2, 2, 62) == 2 and check_int("bits", 62, 2, 62) == 62
    assert check_int("pick", -2, -2, 1) == -2
    for bad in (1, 63):
        with pytest.raises(OptionError, match=r"bits must be an integer in \[2, 62\], got"):
            check_int("bits", bad, 2, 62)
    assert check_int("max_generations", 0, 0) == 0


@pytest.mark.parametrize("value", [0.0, 1e-300, 0.5, 2, "1.5", np.float32(2.0)])
def test_check_number_accepts_the_closed_interval(value):
    got = check_number("F", value, 0.0, 2.0)
    assert got == float(value) and type(got) is float


@pytest.mark.parametrize("value", [-1e-12, 2.0000001, np.inf, -np.inf, np.nan, "big", None, True, [1.0]])
def test_check_number_rejects_the_rest_naming_option_and_range(value):
    with pytest.raises(OptionError, match=r"F must be a finite number in \[0, 2\], got"):
        check_number("F", value, 0.0, 2.0)


def test_check_number_open_ends_one_sided_ranges_and_units():
    with pytest.raises(OptionError, match=r"F_min must be a finite number in \(0, 2\], got 0"):
        check_number("F_min", 0.0, 0.0, 2.0, open_low=True)
    with pytest.raises(OptionError, match=r"x must be a finite number in \[0, 1\), got 1"):
        check_number("x", 1.0, 0.0, 1.0, open_high=True)
    assert check_number("x", 0.999, 0.0, 1.0, open_high=True) == 0.999
    with pytest.raises(OptionError, match=r"x must be a finite number >= 3 m, got 2"):
        check_number("x", 2, 3.0, unit="m")
    with pytest.raises(OptionError, match=r"x must be a finite number <= -1, got 0"):
        check_number("x", 0, high=-1.0)
    assert check_number("cost_tolerance", -5.0) == -5.0  # no range: any finite number
    with pytest.raises(OptionError, match=r"cost_tolerance must be a finite number, got nan"):
        check_number("cost_tolerance", float("nan"))


def test_check_positive():
    assert check_positive("xatol", 1e-10) == 1e-10
    assert check_positive("F", 2.0, 2.0) == 2.0
    for bad in (0.0, -1.0, np.inf, np.nan, "x", False):
        with pytest.raises(OptionError, match=r"xatol must be a finite number > 0, got"):
            check_positive("xatol", bad)
    with pytest.raises(OptionError, match=r"F must be a finite number in \(0, 2\], got 3"):
        check_positive("F", 3.0, 2.0)
    with pytest.raises(OptionError, match=r"length_scale must be a finite number > 0 m, got -1"):
        check_positive("length_scale", -1, unit="m")


def test_check_nonnegative():
    assert check_nonnegative("eta", 0) == 0.0 and check_nonnegative("eta", 100.0) == 100.0
    assert check_nonnegative("c1", 10.0, 10.0) == 10.0
    for bad in (-1e-9, np.inf, np.nan, "x"):
        with pytest.raises(OptionError, match=r"eta must be a finite number >= 0, got"):
            check_nonnegative("eta", bad)
    with pytest.raises(OptionError, match=r"c1 must be a finite number in \[0, 10\], got 20"):
        check_nonnegative("c1", 20.0, 10.0)


@pytest.mark.parametrize("value", [0, 0.0, 0.3, 1, 1.0])
def test_check_fraction_accepts_0_to_1(value):
    assert check_fraction("CR", value) == float(value)


@pytest.mark.parametrize("value", [-0.1, 1.5, np.nan, "most", None])
def test_check_fraction_rejects_the_rest(value):
    with pytest.raises(OptionError, match=r"CR must be a finite number in \[0, 1\], got"):
        check_fraction("CR", value)


def test_check_choice():
    choices = ("clip", "reflect", "resample")
    assert check_choice("bound_handling", "reflect", choices) == "reflect"
    for bad in ("wrap", None, 3, np.array(["clip", "clip"]), ["clip"]):
        with pytest.raises(OptionError, match=r"bound_handling .* is not one of 'clip', 'reflect', 'resample'"):
            check_choice("bound_handling", bad, choices)


def test_check_callback():
    assert check_callback(None) is None
    assert check_callback(print) is print
    for bad in (3, "print"):
        with pytest.raises(OptionError, match=r"callback must be None or callable as callback\(generation, "
                                              r"population\), got"):
            check_callback(bad)
    with pytest.raises(OptionError, match=r"callable as callback\(generation, positions\)"):
        check_callback(3, "callback(generation, positions)")


def test_check_nonnegative_vector():
    got = check_nonnegative_vector("gains", [1, 0.0, 2.5], 3)
    assert got.dtype == float and np.array_equal(got, [1.0, 0.0, 2.5])
    with pytest.raises(OptionError, match=r"gains must have 3 values \(one per joint\), got 2"):
        check_nonnegative_vector("gains", [1.0, 2.0], 3)
    for bad in ([1.0, -1.0, 0.0], [1.0, np.inf, 0.0], [np.nan, 1.0, 1.0]):
        with pytest.raises(OptionError, match=r"gains must be finite values >= 0, got"):
            check_nonnegative_vector("gains", bad, 3)
    with pytest.raises(OptionError, match=r"gains must be 3 finite numbers >= 0 \(one per joint\), got"):
        check_nonnegative_vector("gains", ["a", "b", "c"], 3)
