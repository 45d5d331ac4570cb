"""Records every participant output on the macro-step time grid.

Each output carries the time it describes (see :mod:`orchestrator.participant`).  The
time series has one row per communication point; a participant's value in a row is its
latest output at or before that time (zero-order hold, as the master exchanges it).
Array outputs become one column per element: ``nav.reference[3,1]``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd


class Recorder:
    """Collects ``(time, outputs)`` of each participant during a run.

    Parameters
    ----------
    start_s, dt_s : float
        Start time and macro step [s].
    steps : int
        Number of macro steps planned.
    """

    def __init__(self, start_s: float, dt_s: float, steps: int) -> None:
        self.start_s = start_s
        self.dt_s = dt_s
        self.steps = steps
        self._rows: dict[str, list[tuple[float, dict[str, float]]]] = {}

    def add(self, participant: str, time_s: float, outputs) -> None:
        flat = {}
        for port, value in outputs.items():
            column = f"{participant}.{port}"
            if type(value) is float:
                flat[column] = value
            elif isinstance(value, np.ndarray):
                if value.ndim == 0:
                    flat[column] = float(value)
                for index in np.ndindex(value.shape):
                    flat[f"{column}[{','.join(map(str, index))}]"] = float(value[index])
            else:
                flat[column] = float(value)
        self._rows.setdefault(participant, []).append((time_s, flat))

    def last_time(self) -> float:
        """Latest time any output describes [s]."""
        times = [rows[-1][0] for rows in self._rows.values() if rows]
        return max(times) if times else self.start_s

    def to_frame(self, until_s: float | None = None) -> pd.DataFrame:
        """The time series as a DataFrame with a ``time_s`` column.

        Rows cover the communication points up to ``until_s`` (default: the latest
        recorded time).
        """
        until = self.last_time() if until_s is None else until_s
        count = int(np.floor((until - self.start_s) / self.dt_s + 1e-9)) + 1
        grid = np.round(self.start_s + self.dt_s * np.arange(max(count, 1)), 6)
        frame = pd.DataFrame({"time_s": grid})
        for participant, rows in self._rows.items():
            times = np.round(np.array([time for time, _ in rows]), 6)  # float stamps meet the grid
            part = pd.DataFrame([values for _, values in rows])
            part.insert(0, "time_s", times)
            # keep the last record for a time (a step's outputs replace set-up outputs)
            part = part.drop_duplicates("time_s", keep="last").sort_values("time_s")
            frame = pd.merge_asof(frame, part, on="time_s", direction="backward", tolerance=None)
        return frame
