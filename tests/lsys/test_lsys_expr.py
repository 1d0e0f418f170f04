import numpy as np
import pytest
from hypothesis import given, strategies as st

from ramure.errors import GrammarError
from ramure.lsys.expr import compile_expression, parse_expression


def ev(text, **params):
    fn = compile_expression(parse_expression(text), list(params), {"k": 2.0})
    return fn({k: np.atleast_1d(np.asarray(v, float)) for k, v in params.items()}, {"k": 2.0}, np.random.default_rng(0), 1)[0]


@pytest.mark.parametrize(
    "text,value",
    [
        ("1 + 2 * 3", 7),
        ("(1 + 2) * 3", 9),
        ("-2^2", -4),
        ("2^3^2", 512),
        ("10 / 4", 2.5),
        ("sin(90)", 1),
        ("cos(180)", -1),
        ("atan(1)", 45),
        ("sqrt(16) + abs(-2)", 6),
        ("min(3, 4) + max(3, 4)", 7),
        ("floor(2.7) + ceil(2.1)", 5),
        ("exp(0) + log(1)", 1),
        ("1 < 2 && 2 < 1", 0),
        ("1 < 2 || 2 < 1", 1),
        ("!(1 = 1)", 0),
        ("3 == 3", 1),
        ("3 != 3", 0),
        ("2 >= 2", 1),
        ("k * 3", 6),
        ("1.5e1", 15),
        ("atan2(1, 0) + atan2(0, -1)", 270),
        ("round(2.5) + round(3.5) + round(-0.4)", 6),
        ("int(-1.7) + int(1.7)", 0),
        ("2^3", 8),
    ],
)
def test_values(text, value):
    assert ev(text) == pytest.approx(value)


@given(st.floats(-1e3, 1e3), st.floats(-1e3, 1e3))
def test_arithmetic_matches_python(a, b):
    assert ev("x * y + x - y", x=a, y=b) == pytest.approx(a * b + a - b, rel=1e-9, abs=1e-9)


def test_vectorised_over_modules():
    fn = compile_expression(parse_expression("x * k"), ["x"], {"k": 2})
    out = fn({"x": np.arange(5.0)}, {"k": 3.0}, None, 5)
    assert out.tolist() == [0, 3, 6, 9, 12]


def test_unknown_function_and_name():
    with pytest.raises(GrammarError, match="unknown function 'sine'"):
        parse_expression("sine(3)")
    with pytest.raises(GrammarError, match="unknown name 'zz'"):
        compile_expression(parse_expression("zz + 1"), [], {})


def test_alea_draws_between_the_smaller_and_the_larger_bound_once():
    e = parse_expression("alea(2, 1) + alea(1, 2) * 0")
    got = compile_expression(e, [], {})({}, {}, np.random.default_rng(7), 4)
    u = np.random.default_rng(7).uniform(1, 2, 4)
    np.testing.assert_array_equal(got, u)  # one draw per module per call, low = min, high = max


def test_power_overflow_is_inf_at_run_time_and_an_error_in_a_constant():
    from ramure.lsys.expr import evaluate_constant

    with np.errstate(over="ignore"):
        assert ev("9^9^9") == np.inf  # no big integers: no hang
    with pytest.raises(GrammarError, match="overflow"):
        evaluate_constant(parse_expression("10^400"), {})
