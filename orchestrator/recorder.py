"""Records every participant output on the macro-step time grid, streamed to Parquet as the run goes.

Each output carries the time it describes (see :mod:`orchestrator.participant`).  The
time series has one row per communication point; a participant's value in a row is its
latest output at or before that time (zero-order hold, as the master exchanges it).
Array outputs become one column per element: ``nav.reference[3,1]``.

A row is final once the master has stepped every participant due at its time: a later
step only produces outputs stamped later.  The master then calls :meth:`Recorder.advance`
and the row joins a buffer; every :data:`CHUNK_ROWS` rows the buffer is written as one
complete Parquet part into the spool folder, so the memory a run holds does not grow with
its length and what was written can be read back at any time (a watchdog's emergency
write).  :meth:`Recorder.write_parquet` merges the parts into one file, one row group per
part, under one schema: a column that appears late (a participant that only starts giving
an output after a while) is NaN in the rows before.  Without a spool folder the rows stay
in memory (tests, benchmarks).

:class:`ColumnFrame` reads a Parquet time series one column at a time: what the analyses
and figures get, so that they, too, hold only the columns they use.
"""

from __future__ import annotations

import errno
import logging
import math
import shutil
from pathlib import Path

import numpy as np
import pandas as pd

from orchestrator.errors import ResultsError

log = logging.getLogger(__name__)

#: Rows per Parquet row group written during the run.
CHUNK_ROWS = 512
#: Decimal places of the grid times (float stamps meet the grid).
TIME_DECIMALS = 6


class Recorder:
    """Collects ``(time, outputs)`` of each participant during a run.

    Parameters
    ----------
    start_s, dt_s : float
        Start time and macro step [s].
    steps : int
        Number of macro steps planned.
    spool : Path, optional
        Folder for the Parquet parts written during the run (created when needed); None
        keeps every row in memory.
    chunk_rows : int
        Rows per row group.
    """

    def __init__(self, start_s: float, dt_s: float, steps: int, spool: Path | None = None,
                 chunk_rows: int = CHUNK_ROWS) -> None:
        self.start_s = start_s
        self.dt_s = dt_s
        self.steps = steps
        self.spool = None if spool is None else Path(spool)
        self.chunk_rows = chunk_rows
        # outputs not yet in a row, in order: (time, their columns, their values as floats)
        self._pending: list[tuple[float, _Columns, tuple[float, ...]]] = []
        self._columns: list[str] = ["time_s"]
        self._position: dict[str, int] = {"time_s": 0}  # column -> its place in a row
        # the latest value of every column applied to the rows, in the order of ``_columns``
        # (a row is a copy of it)
        self._held: list[float] = [start_s]
        # participant -> its ports (as given, in order) -> their columns, for outputs all floats
        self._float_rows: dict[str, dict[tuple[str, ...], _Columns]] = {}
        # (participant, ports, shape of each or None) -> the columns of outputs with arrays
        self._mixed: dict[tuple, _Columns] = {}
        self._latest = start_s  # latest time any output describes
        self._rows: list[list[float]] = []  # emitted rows not yet written (all rows without a spool)
        self._emitted = 0  # grid rows emitted so far
        self._parts: list[Path] = []  # complete Parquet files of CHUNK_ROWS rows each
        self._cells: dict[tuple[str, tuple[int, ...]], list[str]] = {}  # array outputs' column names

    # -- the master's side -------------------------------------------------------------------
    def add(self, participant: str, time_s: float, outputs) -> None:
        """``participant``'s outputs describing ``time_s``: they enter the rows from the first
        grid time at or after it (:meth:`advance`)."""
        values = tuple(outputs.values())
        if set(map(type, values)) <= FLOAT:  # all floats: their columns named once per set of ports
            self.add_floats(time_s, self.float_columns(participant, tuple(outputs)), values)
            return
        stamp = on_grid_decimals(time_s)
        if stamp > self._latest:
            self._latest = stamp
        # arrays and other numbers: the columns named once per set of ports and shapes
        layout = (participant, tuple(outputs),
                  tuple(value.shape if isinstance(value, np.ndarray) else None for value in values))
        columns = self._mixed.get(layout)
        if columns is None:
            columns = self._mixed[layout] = self._mixed_columns(participant, outputs)
        self._pending.append((stamp, columns, _flat_values(values)))

    def _mixed_columns(self, participant: str, outputs) -> "_Columns":
        """The columns of outputs that are not all floats, in the order :func:`_flat_values` gives
        their values (an array's cells after it).  Two with the same name (a port named as
        another's cell) are one column, set in that order: the later value holds, as in a dict."""
        names = []
        for port, value in outputs.items():
            column = f"{participant}.{port}"
            if isinstance(value, np.ndarray):
                if value.ndim == 0:
                    names.append(column)
                names.extend(self._cell_columns(column, value.shape))
            else:
                names.append(column)
        return _Columns(tuple(names))

    def float_columns(self, participant: str, ports: tuple[str, ...]) -> "_Columns":
        """The columns of ``participant``'s outputs ``ports`` (in that order), for :meth:`add_floats`."""
        rows = self._float_rows.get(participant)
        if rows is None:
            rows = self._float_rows[participant] = {}
        columns = rows.get(ports)
        if columns is None:
            columns = rows[ports] = _Columns(tuple(f"{participant}.{port}" for port in ports))
        return columns

    def add_floats(self, time_s: float, columns: "_Columns", values: tuple[float, ...]) -> None:
        """:meth:`add` of outputs that are all Python floats, their columns named once
        (:meth:`float_columns`): what the master's step calls."""
        stamp = time_s if type(time_s) is float and (time_s * 64.0).is_integer() else on_grid_decimals(time_s)
        if stamp > self._latest:
            self._latest = stamp
        self._pending.append((stamp, columns, values))

    def _cell_columns(self, column: str, shape: tuple[int, ...]) -> list[str]:
        """``column[i,j]`` of every cell of an array output of ``shape``, in C order (named once per run)."""
        names = self._cells.get((column, shape))
        if names is None:
            names = self._cells[(column, shape)] = [f"{column}[{','.join(map(str, index))}]"
                                                    for index in np.ndindex(shape)]
        return names

    @property
    def buffered_rows(self) -> int:
        """Rows emitted but not yet written (at most ``chunk_rows`` with a spool)."""
        return len(self._rows)

    def last_time(self) -> float:
        """Latest time any output describes [s]."""
        return self._latest

    def advance(self, until_s: float) -> None:
        """Every participant due up to ``until_s`` has stepped: the rows up to it are final."""
        count = math.floor((until_s - self.start_s) / self.dt_s + 1e-9) + 1
        held, rows = self._held, self._rows
        while self._emitted < count:
            grid = on_grid_decimals(self.start_s + self.dt_s * self._emitted)
            if self._pending:
                keep = []
                for item in self._pending:
                    if item[0] <= grid:
                        stamp, columns, values = item
                        place = columns.place
                        if place is None:  # their first values: the new columns join the rows
                            place = self._place(columns)
                        if type(place) is slice:
                            held[place] = values
                        else:
                            for index, value in zip(place, values):
                                held[index] = value
                    else:
                        keep.append(item)
                self._pending = keep
            held[0] = grid
            rows.append(held.copy())
            self._emitted += 1
            if self.spool is not None and len(rows) >= self.chunk_rows:
                self._flush(self.spool)
                rows = self._rows

    def _place(self, columns: "_Columns"):
        """Where ``columns`` are in a row (a slice where they are side by side), the new ones
        appended in their order."""
        position, held = self._position, self._held
        for name in columns.names:
            if name not in position:
                position[name] = len(self._columns)
                self._columns.append(name)
                held.append(math.nan)
        indices = [position[name] for name in columns.names]
        first = indices[0] if indices else 0
        columns.place = (slice(first, first + len(indices)) if indices == list(range(first, first + len(indices)))
                         else indices)
        return columns.place

    def finish(self) -> None:
        """Emit the rows up to the latest output and write what is buffered (with a spool)."""
        self.advance(self._latest)
        if self.spool is not None:
            self._flush(self.spool)

    # -- reading back ------------------------------------------------------------------------------
    def to_frame(self) -> pd.DataFrame:
        """The whole time series as a DataFrame (short runs, emergency writes: it is all in memory)."""
        frames = [pd.read_parquet(part) for part in self._parts]
        frames.append(self._buffered_frame())
        frames = [frame for frame in frames if len(frame)] or frames[-1:]
        frame = frames[0] if len(frames) == 1 else pd.concat(frames, ignore_index=True)
        return frame.reindex(columns=self._columns)

    def write_parquet(self, target: Path) -> None:
        """Write the time series to ``target`` (after :meth:`finish`): one file, one schema."""
        if self.spool is None:
            self.to_frame().to_parquet(target, index=False)
            return
        self._guard(lambda: self._merge_parts(target), target)

    def write_csv(self, target: Path) -> None:
        """Write the time series to ``target`` as CSV, one spool part at a time (after :meth:`finish`)."""
        if self.spool is None:
            self.to_frame().to_csv(target, index=False)
            return

        def write() -> None:
            header = True
            for part in self._parts:
                chunk = pd.read_parquet(part).reindex(columns=self._columns)
                chunk.to_csv(target, index=False, header=header, mode="w" if header else "a")
                header = False
            if header:
                pd.DataFrame(columns=self._columns).to_csv(target, index=False)

        self._guard(write, target)

    def discard_spool(self) -> None:
        """Remove the spool folder (its parts were merged, or are not wanted)."""
        if self.spool is not None:
            shutil.rmtree(self.spool, ignore_errors=True)

    # -- writing ---------------------------------------------------------------------------------
    def _buffered_values(self) -> np.ndarray:
        """The buffered rows as one (rows, columns) array, NaN where a column had not appeared yet."""
        width = len(self._columns)
        return np.array([row + [np.nan] * (width - len(row)) for row in self._rows], dtype=float).reshape(-1, width)

    def _buffered_frame(self) -> pd.DataFrame:
        return pd.DataFrame(self._buffered_values(), columns=self._columns)

    def _buffered_table(self):
        """The buffered rows as an Arrow table, as ``pyarrow.Table.from_pandas`` of
        :meth:`_buffered_frame` has them (NaN stored as null) without going through pandas."""
        import pyarrow as pa

        values = self._buffered_values()
        return pa.Table.from_arrays([pa.array(values[:, k], from_pandas=True) for k in range(values.shape[1])],
                                    names=self._columns)

    def _flush(self, spool: Path) -> None:
        """Write the buffered rows as one complete Parquet part into ``spool`` (readable at once, even
        mid-run)."""
        if not self._rows:
            return

        def write() -> None:
            import pyarrow.parquet as pq

            spool.mkdir(parents=True, exist_ok=True)
            part = spool / f"part-{len(self._parts):05d}.parquet"
            pq.write_table(self._buffered_table(), part)
            self._parts.append(part)
            self._rows = []

        self._guard(write, spool)

    def _merge_parts(self, target: Path) -> None:
        import pyarrow as pa
        import pyarrow.parquet as pq

        schema = pa.schema([pa.field(column, pa.float64()) for column in self._columns])
        with pq.ParquetWriter(target, schema) as writer:
            for part in self._parts:
                table = pq.read_table(part)
                present = set(table.column_names)  # (each column_names is a new list)
                columns = [table.column(name) if name in present
                           else pa.array(np.full(table.num_rows, np.nan)) for name in self._columns]
                writer.write_table(pa.Table.from_arrays(columns, schema=schema))

    @staticmethod
    def _guard(write, where: Path):
        """Run ``write``; a full disk or an unwritable folder becomes a :class:`ResultsError`."""
        try:
            return write()
        except OSError as exc:
            reason = "the disk is full" if exc.errno in (errno.ENOSPC, errno.EDQUOT) else (exc.strerror or str(exc))
            raise ResultsError(f"{where}: the time series could not be written ({reason})") from exc


#: The set of the types of outputs that are all Python floats.
FLOAT = frozenset({float})


_FLOAT64 = np.dtype(np.float64)


def _flat_values(values) -> tuple[float, ...]:
    """Outputs as floats, an array as its own ``float()`` (0-d) and then ``float(cell)`` of each
    cell in C order (a real array's in one pass)."""
    flat: list[float] = []
    for value in values:
        if type(value) is float:
            flat.append(value)
        elif isinstance(value, np.ndarray):
            if value.ndim == 0:
                flat.append(float(value))
            if value.dtype is _FLOAT64:  # its cells are floats as they come
                flat.extend(value.ravel().tolist())
            elif value.dtype.kind in "fiub":
                flat.extend(map(float, value.ravel().tolist()))
            else:
                flat.extend(float(value[index]) for index in np.ndindex(value.shape))
        else:
            flat.append(float(value))
    return tuple(flat)


def on_grid_decimals(time_s: float) -> float:
    """``round(time_s, TIME_DECIMALS)``, without rounding a time that is a whole number of
    64ths of a second (as a grid of whole, half or quarter seconds is): such a time has at most
    six decimals, so rounding returns it unchanged, and ``round`` to decimals is the slowest
    part of recording an output."""
    if type(time_s) is float and (time_s * 64.0).is_integer():
        return time_s
    return round(float(time_s), TIME_DECIMALS)


class _Columns:
    """The columns of a set of outputs, in their order, and where they are in a row once known."""

    __slots__ = ("names", "place")

    def __init__(self, names: tuple[str, ...]) -> None:
        self.names = names
        self.place: slice | list[int] | None = None


class ColumnFrame:
    """A Parquet time series read one column at a time, with the DataFrame access analyses use.

    Supports ``frame.columns``, ``len(frame)``, ``name in frame.columns``, ``frame[name]``
    and ``frame.get(name, default)`` (a :class:`pandas.Series`), ``frame[[a, b]]`` (a
    DataFrame of those columns) and ``frame.iloc[a:b]`` (a view of those rows), each reading
    only what it needs.  Any other DataFrame attribute reads the whole series once and
    answers from it; :meth:`to_pandas` reads it all.
    """

    def __init__(self, path: Path, rows: slice = slice(None)) -> None:
        import pyarrow.parquet as pq

        self.path = Path(path)
        self._file = pq.ParquetFile(self.path)
        self.columns = pd.Index(self._file.schema_arrow.names)
        self._rows = rows
        self._count = len(range(self._file.metadata.num_rows)[rows])
        self._whole: pd.DataFrame | None = None

    def __len__(self) -> int:
        return self._count

    def __getitem__(self, name):
        if isinstance(name, list):  # several columns: a DataFrame of those only
            missing = [column for column in name if column not in self.columns]
            if missing:
                raise KeyError(missing)
            return self._file.read(columns=name).to_pandas().iloc[self._rows].reset_index(drop=True)
        if not isinstance(name, str) or name not in self.columns:
            raise KeyError(name)
        values = self._file.read(columns=[name]).column(0).to_numpy()[self._rows]
        return pd.Series(values, name=name)

    def __getattr__(self, name: str):
        """Any other DataFrame attribute: the whole series is read once (for analyses written
        against a DataFrame; they then hold it all, as before streaming)."""
        if name.startswith("_"):
            raise AttributeError(name)
        log.debug("analysis used DataFrame.%s: reading the whole time series %s", name, self.path)
        if self._whole is None:
            self._whole = self.to_pandas()
        return getattr(self._whole, name)

    def __contains__(self, name: str) -> bool:
        return name in self.columns

    def get(self, name: str, default=None):
        """``frame[name]``, or ``default`` for a column the series does not have."""
        return self[name] if isinstance(name, str) and name in self.columns else default

    @property
    def iloc(self) -> "_RowSlicer":
        return _RowSlicer(self)

    def to_pandas(self) -> pd.DataFrame:
        return self._file.read().to_pandas().iloc[self._rows].reset_index(drop=True)


class _RowSlicer:
    def __init__(self, frame: ColumnFrame) -> None:
        self._frame = frame

    def __getitem__(self, rows):
        if not isinstance(rows, slice):  # a row, or rows by position: as a DataFrame would give them
            return self._frame.to_pandas().iloc[rows]
        span = range(self._frame._file.metadata.num_rows)[self._frame._rows][rows]
        return ColumnFrame(self._frame.path, slice(span.start, span.stop, span.step))
