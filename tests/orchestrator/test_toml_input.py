"""The TOML reading every input file shares: its limits, its field types at their edges, and
each refusal as the one line the user reads."""

from typing import Annotated, Any

import pytest
from pydantic import ValidationInfo, field_validator

from orchestrator import toml_input
from orchestrator.errors import ScenarioError
from orchestrator.toml_input import (FolderName, NonNegative, NonNegativeInt, PairNm, Positive, PositiveInt, Text,
                                     TomlTable, check_nesting, checked, fail, fail_whole, is_finite_number,
                                     message_of, one_of, read_toml, shown, shown_text)


class Fields(TomlTable):
    positive: Positive = 1.0
    non_negative: NonNegative = 0.0
    positive_int: PositiveInt = 1
    non_negative_int: NonNegativeInt = 0
    text: Text = "t"
    pair: PairNm = (0.0, 0.0)
    folder: FolderName = "f"


def refusal(**values) -> str:
    with pytest.raises(ScenarioError) as raised:
        checked(Fields, values, "file.toml", ("table",))
    return str(raised.value)


@pytest.mark.parametrize("key, value", [
    ("positive", 0.5), ("positive", 1e-300), ("non_negative", 0), ("non_negative", 0.5),
    ("positive_int", 1), ("non_negative_int", 0), ("non_negative_int", 3), ("text", "x"), ("pair", [1, -2.5]),
    ("folder", "a" * toml_input.MAX_NAME_CHARS),
])
def test_values_at_the_edge_are_taken(key, value):
    assert getattr(checked(Fields, {key: value}, "file.toml"), key) == (tuple(value) if key == "pair" else value)


@pytest.mark.parametrize("key, value, problem", [
    ("positive", 0, "must be positive, got 0"),
    ("positive", -0.5, "must be positive, got -0.5"),
    ("positive", "1", "must be a finite number, got '1'"),
    ("non_negative", -0.5, "must not be negative, got -0.5"),
    ("non_negative", float("inf"), "must be a finite number, got inf"),
    ("positive_int", 0, "must be a positive integer, got 0"),
    ("positive_int", 1.5, "must be a positive integer, got 1.5"),
    ("positive_int", 1.0, "must be a positive integer, got 1.0"),
    ("positive_int", True, "must be a positive integer, got True"),
    ("non_negative_int", -1, "must be a non-negative integer, got -1"),
    ("non_negative_int", 0.5, "must be a non-negative integer, got 0.5"),
    ("non_negative_int", False, "must be a non-negative integer, got False"),
    ("text", "", "must be a non-empty string, got ''"),
    ("text", 5, "must be a non-empty string, got 5"),
    ("pair", [1, 2, 3], "must be [north, east] in nm, got [1, 2, 3]"),
    ("pair", [1, "a"], "must be [north, east] in nm, got [1, 'a']"),
    ("pair", "ab", "must be [north, east] in nm, got 'ab'"),
    ("folder", 5, "must be a non-empty string, got 5"),
    ("folder", "a" * 101, "must be at most 100 characters long, got 101"),
    ("folder", "a/b", "must be a folder name without slashes or any of /\\:*?\"<>|, got 'a/b'"),
    ("folder", " run", "must not start with '.', start or end with a space, or be a reserved device name, got ' run'"),
    ("folder", "nul", "must not start with '.', start or end with a space, or be a reserved device name, got 'nul'"),
])
def test_a_value_beyond_the_edge_is_refused_with_the_value(key, value, problem):
    assert refusal(**{key: value}) == f"file.toml: 'table.{key}' {problem}"


def test_one_of_takes_only_its_choices():
    class Exchange(TomlTable):  # built here, not at import: the validator is made when the test runs
        order: Annotated[str, one_of(("jacobi", "gauss-seidel"))] = "jacobi"

    assert checked(Exchange, {"order": "gauss-seidel"}, "file.toml").order == "gauss-seidel"
    for value, got in (("seidel", "'seidel'"), (5, "5")):
        with pytest.raises(ScenarioError) as raised:
            checked(Exchange, {"order": value}, "file.toml")
        assert str(raised.value) == f"file.toml: 'order' must be one of jacobi, gauss-seidel, got {got}"


def test_numbers_too_large_for_a_float_are_not_finite():
    assert not is_finite_number(10 ** 400)
    assert is_finite_number(10 ** 300)


def test_a_failure_reads_as_its_message():
    assert fail("must be blue").message() == "must be blue"
    assert fail_whole("give '{prefix}a'").message() == "give '{prefix}a'"


def test_messages_are_shown_on_one_line_and_cut():
    assert shown_text("a\nb\x00") == "a\\nb\\x00"
    assert shown_text("x" * 60) == "x" * 60
    assert shown_text("x" * 61) == "x" * 57 + "..."
    assert shown_text("abcdefghij", 8) == "abcde..."
    deep = []
    for _ in range(100_000):
        deep = [deep]
    assert shown(deep) == "<list nested too deeply>"


def test_nesting_is_counted_to_the_limit_for_tables_and_arrays():
    check_nesting({"a": {"b": {"c": 1}}}, "file.toml", limit=3)
    check_nesting([[[1]]], "file.toml", limit=3)
    check_nesting({"a": [{"b": 1}]}, "file.toml", limit=3)
    with pytest.raises(ScenarioError) as raised:
        check_nesting({"a": {"b": {"c": {"d": 1}}}}, "file.toml", limit=3)
    assert str(raised.value) == "file.toml: 'a.b.c.d' nests arrays or tables deeper than the limit of 3 levels"
    with pytest.raises(ScenarioError, match=r"^file.toml: 'a\[0\]\[0\]\[0\]' nests"):
        check_nesting({"a": [[[1]]]}, "file.toml", limit=3)


def test_a_file_over_the_size_limit_is_refused_unread(tmp_path, monkeypatch):
    monkeypatch.setattr(toml_input, "MAX_FILE_BYTES", 10)
    path = tmp_path / "file.toml"
    path.write_text("a = 12345\n")  # 10 bytes: at the limit
    assert read_toml(path, "scenario")[0] == {"a": 12345}
    path.write_text("a = 123456\n")
    with pytest.raises(ScenarioError) as raised:
        read_toml(path, "scenario")
    assert str(raised.value) == f"{path}: scenario file of 11 bytes is larger than the limit of 10"


def test_a_file_that_is_not_toml_says_where_the_parser_stopped(tmp_path):
    path = tmp_path / "file.toml"
    path.write_text("a = = 1\n")
    with pytest.raises(ScenarioError) as raised:
        read_toml(path, "scenario")
    assert str(raised.value) == f"{path}: not valid TOML: Invalid value (at line 1, column 5)"
    path.write_bytes(b"a = '\xff\xfe'\n")
    with pytest.raises(ScenarioError) as raised:
        read_toml(path, "scenario")
    assert str(raised.value) == (f"{path}: not valid TOML: 'utf-8' codec can't decode byte 0xff in position 5: "
                                 "invalid start byte")


def test_a_long_parser_message_is_cut_to_200_characters(tmp_path):
    path = tmp_path / "file.toml"
    key = "k" * 138  # the parser's message is then 201 characters long
    path.write_text(f"{key} = {{b = 1}}\n{key}.c = 2\n")
    with pytest.raises(ScenarioError) as raised:
        read_toml(path, "scenario")
    shown_part = str(raised.value).removeprefix(f"{path}: not valid TOML: ")
    assert len(shown_part) == 200 and shown_part.startswith("Cannot mutate immutable namespace ('kkk")
    assert shown_part.endswith(" (at line 2, column ...")


def test_an_integer_too_long_to_convert_is_refused_in_a_message_cut_to_120_characters(tmp_path):
    path = tmp_path / "file.toml"
    path.write_text("a = " + "9" * 5000 + "\n")  # Python's own message is 140 characters long
    with pytest.raises(ScenarioError) as raised:
        read_toml(path, "scenario")
    shown_part = str(raised.value).removeprefix(f"{path}: not valid TOML: ")
    assert len(shown_part) == 120 and shown_part.startswith("Exceeds the limit (4300 digits) for integer string")
    assert shown_part.endswith("...")


def test_pydantics_own_errors_read_as_one_line():
    where = "file.toml"
    assert message_of({"type": "dict_type", "loc": ("a", 0), "msg": "Input should be a dict.", "input": 5},
                      where) == "file.toml: 'a[0]': input should be a dict, got 5"
    assert message_of({"type": "odd", "loc": ("a",)}, where) == "file.toml: 'a': is not valid, got None"
    assert message_of({"type": "odd", "loc": ("a",), "msg": "Value should be X.", "input": 1}, where) == (
        "file.toml: 'a': value should be X, got 1")  # only the full stop is dropped
    assert message_of({"type": "unknown_key", "loc": ("a",), "ctx": {"key": "b", "valid": "c, d"}}, where) == (
        "file.toml: unknown key 'a.b' (valid: c, d)")
    assert message_of({"type": "extra_forbidden", "loc": ("a", "b")}, where) == "file.toml: unknown key 'a.b'"
    assert message_of({"type": "missing", "loc": ("b",)}, where, ("a",)) == "file.toml: missing key 'a.b'"
    whole = {"type": "rhnc_whole", "loc": (), "ctx": {"message": "give '{prefix}x' or '{key}'"}}
    assert message_of(whole, where) == "file.toml: give 'x' or ''"
    assert message_of(whole, where, ("t",)) == "file.toml: give 't.x' or 't'"


class Scaled(TomlTable):
    value: float

    @field_validator("value")
    @classmethod
    def _scaled(cls, value: Any, info: ValidationInfo) -> float:
        return value * (info.context or {}).get("factor", 1.0)


def test_checked_passes_its_context_to_the_validators():
    assert checked(Scaled, {"value": 2.0}, "file.toml", context={"factor": 3.0}).value == 6.0


@pytest.mark.parametrize("separator", ["=", ",", "[", "{"])
def test_the_item_count_takes_each_separator_and_stops_just_past_the_limit(separator):
    half = toml_input.MAX_ITEMS // 2
    toml_input.prescan_toml("=" * half + separator * (toml_input.MAX_ITEMS - half), "f.toml")   # at the limit
    with pytest.raises(ScenarioError, match=rf"^f\.toml: holds {toml_input.MAX_ITEMS + 1} keys, values and tables"):
        toml_input.prescan_toml("=" * half + separator * (toml_input.MAX_ITEMS - half + 1), "f.toml")


def test_a_distance_at_the_top_level_is_named_by_its_own_key():
    with pytest.raises(ScenarioError, match=r"^f\.toml: 'goal_nm\[0\]' must lie within"):
        toml_input.check_distances_nm({"goal_nm": [1e9, 0.0]}, "f.toml", "")


def test_a_pair_in_nm_may_lie_at_the_bound_and_a_pair_beyond_it_is_quoted():
    class Table(toml_input.TomlTable):
        at_nm: PairNm

    bound = toml_input.MAX_DISTANCE_NM
    assert Table.model_validate({"at_nm": [bound, -bound]}).at_nm == (bound, -bound)
    with pytest.raises(ScenarioError, match=r"got \[1e\+?0?9, 0\.0\]$|got \[1000000000\.0, 0\.0\]$"):
        toml_input.checked(Table, {"at_nm": [1e9, 0.0]}, "f.toml")


def test_a_distance_exactly_at_the_bound_is_taken():
    bound = toml_input.MAX_DISTANCE_NM
    toml_input.check_distances_nm({"goal_nm": [bound, -bound]}, "f.toml", "")
