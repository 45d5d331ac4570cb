"""Comparison files checked by pydantic models (the format: ``docs/compare-format.md``).

The file's own keys are checked here, and file names in its overrides are resolved against
the comparison file's folder (:func:`resolve_paths`); a table named after a comparison extension
(``[voyage]``) is handed to that extension, which checks it.  Messages name the file and
the key; a sweep is bounded (:data:`MAX_SWEEP_MEMBERS`) before it is expanded.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

from pydantic import PlainValidator, model_validator

from orchestrator.errors import ScenarioError
from orchestrator.toml_input import FolderName, Table, TomlTable, checked, fail, fail_whole, read_toml, shown_text

#: Most members of one ``[sweep]`` (each member is a whole comparison).
MAX_SWEEP_MEMBERS = 10_000
KEYS = ("name", "analysis", "metrics", "baseline", "runs", "set", "sweep")
RUN_KEYS = ("label", "scenario", "set", "paper", "figures")


def _string(value: Any) -> str:
    if not isinstance(value, str):
        raise fail("must be a string")
    return value


def _overrides(value: Any) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise fail("expected a table of dotted-key overrides")
    for key in value:
        if not key or not all(key.split(".")):
            raise fail(f"key '{shown_text(key)}' is not a dotted key path")
    return dict(value)


Overrides = Annotated[dict, PlainValidator(_overrides)]


#: The default of a key that must be given, where the table's own validator says so in its words
#: (the key keeps its given type: the validator refuses the table while the key is missing).
REQUIRED: Any = None


class RunTable(TomlTable):
    """One ``[[runs]]`` table: a labelled scenario with its overrides and the paper's figures."""

    label: Annotated[str, PlainValidator(_string)] = REQUIRED
    scenario: Annotated[str, PlainValidator(_string)] = REQUIRED
    set: Overrides = {}
    paper: Table = {}
    figures: Table = {}

    @model_validator(mode="after")
    def _named(self):
        if self.label is None or self.scenario is None:
            raise fail_whole("'label' and 'scenario' must be strings")
        return self


def _range(value: Any) -> list[int]:
    if (not isinstance(value, list) or len(value) != 2
            or not all(isinstance(b, int) and not isinstance(b, bool) for b in value) or value[1] < value[0]):
        raise fail("must be [first, last] integers with first <= last")
    if value[1] - value[0] + 1 > MAX_SWEEP_MEMBERS:
        raise fail(f"spans {value[1] - value[0] + 1} members, more than the limit of {MAX_SWEEP_MEMBERS}")
    return list(range(value[0], value[1] + 1))


def _values(value: Any) -> list:
    if not isinstance(value, list) or not value:
        raise fail("must be a non-empty list")
    if len(value) > MAX_SWEEP_MEMBERS:
        raise fail(f"lists {len(value)} members, more than the limit of {MAX_SWEEP_MEMBERS}")
    return value


def _sweep_key(value: Any) -> str:
    if not isinstance(value, str) or not value or not all(value.split(".")):
        raise fail("must be a dotted scenario key, e.g. \"metocean.member\"")
    return value


class SweepTable(TomlTable):
    """``[sweep]``: the whole comparison once per value of one scenario key."""

    key: Annotated[str, PlainValidator(_sweep_key)] = REQUIRED
    values: Annotated[list, PlainValidator(_values)] | None = None
    range: Annotated[list, PlainValidator(_range)] | None = None

    @model_validator(mode="after")
    def _one_source(self):
        if self.key is None:
            raise fail_whole("'{prefix}key' must be a dotted scenario key, e.g. \"metocean.member\"")
        if (self.values is None) == (self.range is None):
            raise fail_whole("give exactly one of '{prefix}values' or '{prefix}range'")
        return self


def _metrics(value: Any) -> list[str]:
    if not isinstance(value, list) or not value or not all(isinstance(m, str) for m in value):
        raise fail("must be a non-empty list of names")
    return value


def _runs(value: Any) -> list:
    if not isinstance(value, list) or not value:
        raise fail_whole("at least one [[runs]] table is needed")
    return value


class ComparisonFile(TomlTable):
    """The comparison's own top-level keys (extension tables are taken off before)."""

    name: FolderName = REQUIRED
    analysis: Annotated[str, PlainValidator(_string)] = REQUIRED
    metrics: Annotated[list, PlainValidator(_metrics)] = REQUIRED
    baseline: Annotated[str, PlainValidator(_string)] | None = None
    runs: Annotated[list, PlainValidator(_runs)] = REQUIRED
    set: Overrides = {}
    sweep: Any = None

    @model_validator(mode="after")
    def _required(self):
        for key in ("name", "analysis"):
            if getattr(self, key) is None:
                raise fail_whole(f"'{key}' must be a string")
        if self.metrics is None:
            raise fail_whole("'metrics' must be a non-empty list of names")
        if self.runs is None:
            raise fail_whole("at least one [[runs]] table is needed")
        return self


def resolve_paths(value: Any, folder: Path, where: str) -> Any:
    """``value`` with the relative file names in it made absolute against ``folder``.

    An override in a comparison file is written there, so a file it names is found beside
    the comparison, not beside each scenario it is applied to.  A string counts as a file
    name when it has a suffix or a folder part (``"storms/gale.nc"``) and names a file
    relative to ``folder``, or when its key is ``file``, which must then exist (an error
    naming ``where`` and the key otherwise).  Tables and lists are searched through.
    """
    if isinstance(value, dict):
        return {key: (_file_value(item, folder, f"{where}.{key}") if key == "file"
                      else resolve_paths(item, folder, f"{where}.{key}")) for key, item in value.items()}
    if isinstance(value, list):
        return [resolve_paths(item, folder, f"{where}[{i}]") for i, item in enumerate(value)]
    if isinstance(value, str) and value and "\0" not in value and not Path(value).is_absolute():
        candidate = folder / value
        if (Path(value).suffix or len(Path(value).parts) > 1) and candidate.exists():
            return str(candidate.resolve())
    return value


def _file_value(value: Any, folder: Path, where: str) -> Any:
    if not isinstance(value, str) or not value or "\0" in value or Path(value).is_absolute():
        return value
    candidate = folder / value
    if not candidate.is_file():
        raise ScenarioError(f"{where}: file not found relative to the comparison file: "
                            f"{shown_text(str(candidate), 300)}")
    return str(candidate.resolve())


def _resolved_overrides(overrides: dict, folder: Path, where: str) -> dict:
    return {key: (_file_value(value, folder, f"{where}.{key}") if key.split(".")[-1] == "file"
                  else resolve_paths(value, folder, f"{where}.{key}")) for key, value in overrides.items()}


def load_comparison(path, extensions: tuple[str, ...] = ()) -> dict[str, Any]:
    """Read and check a comparison file; errors name the file and the key.

    Returns the file's data with its own keys checked and normalised (``set`` tables,
    ``sweep`` as ``{"key", "values"}``); ``extensions`` are the table names handed on.
    """
    path = Path(path)
    data, _ = read_toml(path, "comparison")
    where = str(path)
    valid = KEYS + tuple(extensions)
    for key in data:
        if key not in valid:
            raise ScenarioError(f"{where}: unknown key '{shown_text(key)}' (valid: {', '.join(valid)})")
    top = checked(ComparisonFile, {k: v for k, v in data.items() if k in KEYS}, where)
    labels, runs = [], []
    for i, entry in enumerate(top.runs):
        run = checked(RunTable, entry, where, ("runs", i))
        at = f"{path}: runs[{i}]"
        if run.label in labels:
            raise ScenarioError(f"{at}.label: '{shown_text(run.label)}' is used twice")
        scenario = path.parent / run.scenario
        if "\0" in run.scenario or not scenario.is_file():
            raise ScenarioError(f"{at}.scenario: scenario file not found: {shown_text(str(scenario), 300)}")
        for key in run.paper:
            if key not in top.metrics:
                raise ScenarioError(f"{at}.paper: '{shown_text(key)}' is not one of the metrics")
        runs.append({**entry, "set": _resolved_overrides(run.set, path.parent, f"{at}.set")})
        labels.append(run.label)
    if top.baseline is not None and top.baseline not in labels:
        raise ScenarioError(f"{path}: baseline '{shown_text(top.baseline)}' is not a run label "
                            f"({', '.join(labels)})")
    spec = {**data, "runs": runs, "set": _resolved_overrides(top.set, path.parent, f"{path}: set")}
    if "sweep" in data:
        sweep = checked(SweepTable, data["sweep"], where, ("sweep",))
        values = sweep.values if sweep.values is not None else sweep.range or []  # the table holds one of them
        if sweep.key.split(".")[-1] == "file":
            values = [_file_value(v, path.parent, f"{path}: sweep.values[{i}]") for i, v in enumerate(values)]
        else:
            values = resolve_paths(values, path.parent, f"{path}: sweep.values")
        spec["sweep"] = {"key": sweep.key, "values": values}
    return spec
