"""Reading the toolchain's TOML input files, with limits, and the base of their configuration models.

Every input file (scenario, batch, comparison, offline planning) is read by
:func:`read_toml`, which refuses what could exhaust the machine before anything is
allocated from it: a file over :data:`MAX_FILE_BYTES`, text the parser would take too long
over (:func:`prescan_toml`, before it is parsed), arrays or tables nested deeper than
:data:`MAX_NESTING`.  The tables are then checked by pydantic models derived from
:class:`TomlTable` (unknown keys forbidden, strict types, finite numbers) and a pydantic
``ValidationError`` becomes one :class:`~orchestrator.errors.ScenarioError` line naming the
file and the dotted key (:func:`checked`).
"""

from __future__ import annotations

from typing import TypeGuard
import math
import re
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Annotated, Any, ClassVar, TypeVar

from pydantic import BaseModel, ConfigDict, PlainValidator, ValidationError, model_validator
from pydantic_core import PydanticCustomError

from orchestrator.errors import ScenarioError


def is_finite_number(value) -> TypeGuard[int | float]:
    """True for a finite int or float that is not a bool: what every numeric option must be.

    (TOML's ``true`` is a Python bool, itself an int subclass, so it must be excluded.)
    """
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:  # an int beyond the range of a float (TOML integers are unbounded here)
        return False


#: Largest input file read [bytes]; the shipped ones are below 20 kB.
MAX_FILE_BYTES = 16 * 1024 * 1024
#: Deepest nesting of arrays and tables in an input file (the shipped files nest 6 deep).
MAX_NESTING = 24
#: Most keys, values and tables in an input file, counted before it is parsed (the shipped
#: files hold fewer than 200).
MAX_ITEMS = 20_000
#: Largest distance or coordinate a key in nautical miles may hold [nm]: half the Earth's
#: circumference, farther than any two points at sea are apart.
MAX_DISTANCE_NM = 10_800.0
#: Longest value shown in a message [characters].
SHOWN_CHARS = 60
#: Longest name of a results folder (``simulation.name``, ``batch.name``) [characters].
MAX_NAME_CHARS = 100
#: Characters a results folder name may not hold: path separators and what Windows refuses.
FORBIDDEN_NAME_CHARS = '/\\:*?"<>|'

Model = TypeVar("Model", bound=BaseModel)


# -- reading ---------------------------------------------------------------------------------
def read_toml(path: Path, kind: str) -> tuple[dict, bytes]:
    """Parse a TOML input file; return its data and raw bytes.

    A missing or malformed file reads ``<path>: <kind> file not found`` or
    ``<path>: not valid TOML: <where the parser stopped>``; a file over the size limit or
    nested too deeply is refused before it is parsed or walked further.
    """
    path = Path(path)
    if not path.is_file():
        raise ScenarioError(f"{path}: {kind} file not found")
    size = path.stat().st_size
    if size > MAX_FILE_BYTES:
        raise ScenarioError(f"{path}: {kind} file of {size} bytes is larger than the limit of {MAX_FILE_BYTES}")
    raw = path.read_bytes()
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ScenarioError(f"{path}: not valid TOML: {shown_text(str(exc), 200)}") from exc
    prescan_toml(text, str(path))
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{path}: not valid TOML: {shown_text(str(exc), 200)}") from exc
    except RecursionError as exc:  # the parser recurses once per nesting level
        raise ScenarioError(f"{path}: not valid TOML: arrays or tables nested deeper than the limit of "
                            f"{MAX_NESTING} levels") from exc
    except ValueError as exc:  # an integer of thousands of digits (Python's limit on int conversion)
        raise ScenarioError(f"{path}: not valid TOML: {shown_text(str(exc), 120)}") from exc
    check_nesting(data, str(path))
    return data, raw


#: One part of a TOML key: bare, or a basic or literal string on one line.
_KEY_PART = r"""(?:[A-Za-z0-9_-]++|"(?:[^"\\\n]|\\.)*+"|'[^'\n]*+')"""
#: A key of more than MAX_NESTING dotted parts, starting where no key character precedes.
_DEEP_KEY = re.compile(rf"""(?<![A-Za-z0-9_\-"'])(?:{_KEY_PART}[ \t]*+\.[ \t]*+){{{MAX_NESTING}}}{_KEY_PART}""")


def prescan_toml(text: str, where: str) -> None:
    """Refuse, before it is parsed, TOML text the parser would take too long over.

    Python's TOML parser takes time quadratic in the number of parts of one dotted key or
    table header (a 40 kB key of 20,000 parts took 7.6 s, one of 80 kB 30 s), and a few
    seconds per megabyte of keys and values.  Two counts that cost one pass over the text
    each bound both: no dotted key or header of more than :data:`MAX_NESTING` parts, and no
    more than :data:`MAX_ITEMS` of the characters that open or separate keys, values and
    tables (``=``, ``,``, ``[``, ``{``; counted in strings and comments too, so the count is
    an upper bound).
    """
    items = text.count("=") + text.count(",") + text.count("[") + text.count("{")
    if items > MAX_ITEMS:
        raise ScenarioError(f"{where}: holds {items} keys, values and tables (counted by '=', ',', '[', '{{'), "
                            f"more than the limit of {MAX_ITEMS}")
    deep = _DEEP_KEY.search(text)
    if deep is not None:
        line = text.count("\n", 0, deep.start()) + 1
        raise ScenarioError(f"{where}: line {line}: the key '{shown_text(deep.group())}' has more than the limit of "
                            f"{MAX_NESTING} dotted parts")


def check_nesting(data: Any, where: str, limit: int = MAX_NESTING) -> None:
    """Refuse arrays or tables nested deeper than ``limit`` (walked without recursion)."""
    stack = [(data, 0, "")]
    while stack:
        node, depth, key = stack.pop()
        if depth > limit:
            raise ScenarioError(f"{where}: '{shown_text(key)}' nests arrays or tables deeper than the limit of "
                                f"{limit} levels")
        if isinstance(node, dict):
            stack.extend((value, depth + 1, f"{key}.{k}" if key else str(k)) for k, value in node.items())
        elif isinstance(node, list):
            stack.extend((value, depth + 1, f"{key}[{k}]") for k, value in enumerate(node))


def apply_override(data: dict, dotted: str, value: Any, where: str) -> None:
    """Set ``data[a][b][c] = value`` for ``dotted = "a.b.c"``, creating missing tables.

    A path running through a value that is not a table is an error naming it.
    """
    keys = dotted.split(".")
    if not all(keys):
        raise ScenarioError(f"{where}: override '{shown_text(dotted)}' is not a dotted key path")
    node = data
    for depth, key in enumerate(keys[:-1]):
        child = node.setdefault(key, {})
        if not isinstance(child, dict):
            raise ScenarioError(
                f"{where}: override '{dotted}': '{'.'.join(keys[:depth + 1])}' is a value, not a table"
            )
        node = child
    node[keys[-1]] = value


# -- messages --------------------------------------------------------------------------------
def shown_text(text: str, limit: int = SHOWN_CHARS) -> str:
    """``text`` on one line: control characters escaped, cut to ``limit`` characters."""
    text = "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in str(text))
    return text if len(text) <= limit else text[:limit - 3] + "..."


def shown(value: Any) -> str:
    """A value as a message shows it: its repr on one line, cut to a readable length."""
    try:
        text = repr(value)
    except RecursionError:
        text = f"<{type(value).__name__} nested too deeply>"
    return shown_text(text)


def fail(message: str) -> PydanticCustomError:
    """A check's failure: the message follows the key, ``'<key>' <message>``."""
    return PydanticCustomError("rhnc", "{message}", {"message": message})


def fail_whole(message: str) -> PydanticCustomError:
    """A check's failure whose message places the keys itself: ``{prefix}`` stands for the
    dotted path of the table being checked with a trailing dot, ``{key}`` for it without."""
    return PydanticCustomError("rhnc_whole", "{message}", {"message": message})


def dotted_path(loc: tuple) -> str:
    """``("participants", "ship", "mapping", 0)`` -> ``participants.ship.mapping[0]``."""
    text = ""
    for part in loc:
        if isinstance(part, int):
            text += f"[{part}]"
        else:
            text += ("." if text else "") + shown_text(part)
    return text


def message_of(error: Mapping[str, Any], where: str, prefix: tuple = ()) -> str:
    """One pydantic error as the one-line message the user reads."""
    loc = prefix + tuple(error["loc"])
    key = dotted_path(loc)
    context = error.get("ctx") or {}
    kind = error["type"]
    if kind == "rhnc":
        return f"{where}: '{key}' {context['message']}"
    if kind == "rhnc_whole":
        return f"{where}: " + context["message"].replace("{prefix}", f"{key}." if key else "").replace("{key}", key)
    if kind == "unknown_key":
        unknown = dotted_path(loc + (context["key"],))
        return f"{where}: unknown key '{unknown}'{context.get('hint', '')} (valid: {context['valid']})"
    if kind == "extra_forbidden":
        return f"{where}: unknown key '{key}'"
    if kind == "missing":
        return f"{where}: missing key '{key}'"
    text = str(error.get("msg", "is not valid")).rstrip(".")
    return f"{where}: '{key}': {text[:1].lower() + text[1:]}, got {shown(error.get('input'))}"


def checked(model: type[Model], data: Any, where: str, prefix: tuple = (), context: dict | None = None) -> Model:
    """``model`` validated from ``data``; the first problem as one :class:`ScenarioError` line.

    ``prefix`` is the dotted path of ``data`` in the file (``("participants", "ship")``).
    """
    try:
        return model.model_validate(data, context=context)
    except ValidationError as exc:
        raise ScenarioError(message_of(exc.errors(include_url=False)[0], where, prefix)) from None


# -- the base model and field types ------------------------------------------------------------
class TomlTable(BaseModel):
    """A TOML table: unknown keys forbidden (the message lists the valid ones), strict types.

    Subclasses may set ``key_hints`` (key -> text appended to the unknown-key message).
    """

    model_config = ConfigDict(extra="forbid", strict=True, frozen=True, populate_by_name=True,
                              arbitrary_types_allowed=True)
    key_hints: ClassVar[dict[str, str]] = {}

    @model_validator(mode="before")
    @classmethod
    def _known_keys(cls, data: Any) -> Any:
        if not isinstance(data, dict):
            raise fail(f"must be a table, got {shown(data)}")
        valid = [field.alias or name for name, field in cls.model_fields.items()]
        for key in data:
            if key not in valid:
                raise PydanticCustomError("unknown_key", "unknown key", {
                    "key": key, "valid": ", ".join(valid), "hint": cls.key_hints.get(key, "")})
        return data


def _finite(value: Any) -> float:
    if not is_finite_number(value):
        raise fail(f"must be a finite number, got {shown(value)}")
    return float(value)


def _positive(value: Any) -> float:
    number = _finite(value)
    if number <= 0:
        raise fail(f"must be positive, got {shown(value)}")
    return number


def _non_negative(value: Any) -> float:
    number = _finite(value)
    if number < 0:
        raise fail(f"must not be negative, got {shown(value)}")
    return number


def _positive_int(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise fail(f"must be a positive integer, got {shown(value)}")
    return value


def _non_negative_int(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise fail(f"must be a non-negative integer, got {shown(value)}")
    return value


def _text(value: Any) -> str:
    if not isinstance(value, str) or not value:
        raise fail(f"must be a non-empty string, got {shown(value)}")
    return value


def _table(value: Any) -> dict:
    if not isinstance(value, dict):
        raise fail("must be a table")
    return value


def _pair(value: Any) -> tuple[float, float]:
    if not (isinstance(value, list) and len(value) == 2 and all(is_finite_number(v) for v in value)):
        raise fail(f"must be [north, east] in nm, got {shown(value)}")
    if any(abs(v) > MAX_DISTANCE_NM for v in value):
        raise fail(f"must lie within +-{MAX_DISTANCE_NM:g} nm (half the Earth's circumference), got {shown(value)}")
    return float(value[0]), float(value[1])


def check_distances_nm(table: Any, where: str, prefix: str) -> None:
    """Refuse a number beyond +-:data:`MAX_DISTANCE_NM` under any key ending in ``_nm``.

    Keys carry their unit in their name (``start_nm``, ``goal_nm``, ``x_range_nm``), so the
    bound holds for every participant type and domain table, whether or not it checks the
    value itself; numbers in lists and tables under such a key are checked too.  What is
    not a finite number is left to the table's own checks.
    """
    stack = [(table, prefix, False)]
    while stack:
        node, key, in_nm = stack.pop()
        if isinstance(node, dict):
            stack.extend((value, f"{key}.{k}" if key else str(k), in_nm or str(k).endswith("_nm"))
                         for k, value in node.items())
        elif isinstance(node, list):
            stack.extend((value, f"{key}[{k}]", in_nm) for k, value in enumerate(node))
        elif in_nm and is_finite_number(node) and abs(node) > MAX_DISTANCE_NM:
            raise ScenarioError(f"{where}: '{shown_text(key)}' must lie within +-{MAX_DISTANCE_NM:g} nm (half the "
                                f"Earth's circumference), got {shown(node)}")


_RESERVED_NAMES = re.compile(r"^(con|prn|aux|nul|com\d|lpt\d)(\..*)?$", re.IGNORECASE)


def folder_name_problem(name: Any) -> str | None:
    """Why ``name`` cannot name a results folder, or None when it can."""
    if not isinstance(name, str) or not name:
        return f"must be a non-empty string, got {shown(name)}"
    if len(name) > MAX_NAME_CHARS:
        return f"must be at most {MAX_NAME_CHARS} characters long, got {len(name)}"
    if any(not c.isprintable() for c in name):
        return f"must not contain control characters (NUL, newline, ...), got {shown(name)}"
    if any(c in FORBIDDEN_NAME_CHARS for c in name):
        return f"must be a folder name without slashes or any of {FORBIDDEN_NAME_CHARS}, got {shown(name)}"
    if name.startswith(".") or name != name.strip() or _RESERVED_NAMES.match(name):
        return f"must not start with '.', start or end with a space, or be a reserved device name, got {shown(name)}"
    return None


def one_of(choices: tuple[str, ...]) -> PlainValidator:
    """A validator accepting only one of ``choices`` (strings)."""
    def check(value: Any) -> str:
        if not isinstance(value, str) or value not in choices:
            raise fail(f"must be one of {', '.join(choices)}, got {shown(value)}")
        return value
    return PlainValidator(check)


def default_folder_name(stem: str, key: str, where: str) -> str:
    """The file's stem as the results folder name when ``key`` is not given, if it can be one."""
    problem = folder_name_problem(stem)
    if problem:
        raise ScenarioError(f"{where}: '{key}' is not given and the file name cannot name a results folder: it "
                            f"{problem}; give '{key}'")
    return stem


def _folder_name(value: Any) -> str:
    problem = folder_name_problem(value)
    if problem:
        raise fail(problem)
    return value


#: A finite float (ints accepted; bools, NaN and infinities refused).
Finite = Annotated[float, PlainValidator(_finite)]
#: A finite float > 0.
Positive = Annotated[float, PlainValidator(_positive)]
#: A finite float >= 0.
NonNegative = Annotated[float, PlainValidator(_non_negative)]
#: An int >= 1 (bools refused).
PositiveInt = Annotated[int, PlainValidator(_positive_int)]
#: An int >= 0 (bools refused).
NonNegativeInt = Annotated[int, PlainValidator(_non_negative_int)]
#: A non-empty string.
Text = Annotated[str, PlainValidator(_text)]
#: A table (its entries are checked by whoever reads them).
Table = Annotated[dict, PlainValidator(_table)]
#: Two finite numbers, ``[north, east]`` [nm].
PairNm = Annotated[tuple[float, float], PlainValidator(_pair)]
#: A name that is safe as one results folder (no separators, control characters, leading dot).
FolderName = Annotated[str, PlainValidator(_folder_name)]
