"""A scenario's FMU parameter values checked against the variable's type and declared range
before the FMU sees them: booleans only for Boolean, whole numbers for the integer types
(within a C int), finite numbers within ``[min, max]`` (the variable's own, else its declared
type's)."""

import math
from types import SimpleNamespace

import pytest

from orchestrator.errors import ScenarioError
from orchestrator.fmu_participant import INT32_RANGE, check_parameter_value, declared_range

WHERE = "scenario.toml: participants.vendor.parameters.p"


def variable(kind, minimum=None, maximum=None, declared=None):
    return SimpleNamespace(name="p", type=kind, min=minimum, max=maximum, declaredType=declared)


def check(kind, value, **bounds):
    check_parameter_value(variable(kind, **bounds), value, WHERE, "Vendor.fmu")


def test_the_declared_range_is_the_variables_own_else_its_types_else_unbounded():
    own = SimpleNamespace(min="1", max="3")
    assert declared_range(variable("Real", "2", "7", declared=own)) == (2.0, 7.0)
    assert declared_range(variable("Real", None, "7", declared=own)) == (1.0, 7.0)
    assert declared_range(variable("Real", "2", None, declared=own)) == (2.0, 3.0)
    assert declared_range(variable("Real")) == (-math.inf, math.inf)
    assert declared_range(variable("Real", declared=SimpleNamespace(min=None, max=None))) == (-math.inf, math.inf)


def test_an_unreadable_or_missing_bound_counts_as_none():
    assert declared_range(variable("Real", "n/a", "7")) == (-math.inf, 7.0)
    assert declared_range(SimpleNamespace(name="p", type="Real")) == (-math.inf, math.inf)  # no such attributes
    assert declared_range(SimpleNamespace(name="p", type="Real", declaredType=SimpleNamespace())) == (
        -math.inf, math.inf)


def test_a_boolean_parameter_takes_only_true_or_false():
    check("Boolean", True)
    check("Boolean", False)
    with pytest.raises(ScenarioError) as raised:
        check("Boolean", 1)
    assert str(raised.value) == f"{WHERE}: 'p' is a Boolean parameter of Vendor.fmu, got 1"


@pytest.mark.parametrize("value", [True, "1.0", [1.0], None])
def test_a_number_parameter_refuses_booleans_and_non_numbers(value):
    with pytest.raises(ScenarioError) as raised:
        check("Real", value)
    assert str(raised.value) == f"{WHERE}: 'p' is a Real parameter of Vendor.fmu, got {value!r}"


@pytest.mark.parametrize("value", [math.inf, -math.inf, math.nan])
def test_a_number_parameter_must_be_finite(value):
    with pytest.raises(ScenarioError) as raised:
        check("Real", value)
    assert str(raised.value) == f"{WHERE}: 'p' must be a finite number, got {value!r}"


@pytest.mark.parametrize("kind", ["Integer", "Enumeration", "Int32", "Int8", "UInt16", "UInt64"])
def test_an_integer_parameter_refuses_a_fraction(kind):
    check(kind, 2)
    with pytest.raises(ScenarioError) as raised:
        check(kind, 2.5)
    assert str(raised.value) == f"{WHERE}: 'p' is an {kind} parameter of Vendor.fmu, got 2.5"


def test_an_integer_parameter_is_bounded_by_a_c_int_and_its_declared_range():
    low, high = INT32_RANGE
    check("Integer", low)
    check("Integer", high)
    for value in (low - 1, high + 1):
        with pytest.raises(ScenarioError) as raised:
            check("Integer", value)
        assert str(raised.value) == (f"{WHERE}: {value} is outside the range [{low:g}, {high:g}] that Vendor.fmu "
                                     "declares for 'p'")
    check("Integer", 7, minimum="2", maximum="7")
    with pytest.raises(ScenarioError, match=r": 8 is outside the range \[2, 7\]"):
        check("Integer", 8, minimum="2", maximum="7")
    with pytest.raises(ScenarioError, match=r": 1 is outside the range \[2, 7\]"):
        check("Integer", 1, minimum="2", maximum="7")


def test_a_real_parameter_is_bounded_by_its_declared_range_only():
    check("Real", 3.0e9)  # no C int limit
    check("Real", 1.0, minimum="0", maximum="1")
    check("Real", 0.0, minimum="0", maximum="1")
    with pytest.raises(ScenarioError) as raised:
        check("Real", 1.5, minimum="0", maximum="1")
    assert str(raised.value) == f"{WHERE}: 1.5 is outside the range [0, 1] that Vendor.fmu declares for 'p'"
    with pytest.raises(ScenarioError, match=r": -0.5 is outside the range \[0, 1\]"):
        check("Real", -0.5, minimum="0", maximum="1")
