"""The time series is written in Parquet parts as the run goes: the same table as holding every
row in memory, a bounded number of rows held, late columns filled, a full disk one line."""

import errno
import os

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest

from orchestrator.cli import main
from orchestrator.recorder import ColumnFrame, Recorder


def reference_frame(records, start_s, dt_s):
    """The table by its definition: per participant the latest record at or before each grid time."""
    until = max(t for _, t, _ in records)
    grid = np.round(start_s + dt_s * np.arange(int(np.floor((until - start_s) / dt_s + 1e-9)) + 1), 6)
    frame = pd.DataFrame({"time_s": grid})
    for name in dict.fromkeys(n for n, _, _ in records):
        rows = [(round(t, 6), {f"{name}.{k}": v for k, v in out.items()}) for n, t, out in records if n == name]
        part = pd.DataFrame([values for _, values in rows])
        part.insert(0, "time_s", [t for t, _ in rows])
        part = part.drop_duplicates("time_s", keep="last").sort_values("time_s")
        frame = pd.merge_asof(frame, part, on="time_s", direction="backward")
    return frame


def simulate(recorder, steps=40, dt=2.0):
    """A sampled participant every step, a dynamic one (outputs at step end) every 3 steps, and
    one that gives a second output only from step 25 on; set-up outputs first."""
    records = []

    def add(name, t, outputs):
        recorder.add(name, t, outputs)
        records.append((name, t, outputs))

    add("nav", 0.0, {"a": 0.0})
    add("ship", 0.0, {"x": 100.0})
    add("late", 0.0, {"p": -1.0})
    for k in range(steps):
        t = k * dt
        add("nav", t, {"a": float(k)})
        if k % 3 == 0:
            add("ship", t + min(3, steps - k) * dt, {"x": 100.0 + k})
        add("late", t, {"p": float(k), **({"q": 10.0 * k} if k >= 25 else {})})
        recorder.advance(t)
        yield records


def test_the_streamed_series_equals_the_table_by_definition(tmp_path):
    recorder = Recorder(0.0, 2.0, 40, spool=tmp_path / "spool", chunk_rows=7)
    for records in simulate(recorder):  # noqa: B007 (the last, complete list is read below)
        assert recorder.buffered_rows < 7  # never more than one part's rows in memory
    recorder.finish()
    recorder.write_parquet(tmp_path / "series.parquet")
    written = pd.read_parquet(tmp_path / "series.parquet")
    expected = reference_frame(records, 0.0, 2.0)
    pd.testing.assert_frame_equal(written, expected[written.columns], check_dtype=False)
    assert list(written.columns) == ["time_s", "nav.a", "ship.x", "late.p", "late.q"]
    assert written["late.q"].iloc[:25].isna().all() and written["late.q"].iloc[25] == 250.0
    assert pq.ParquetFile(tmp_path / "series.parquet").num_row_groups == len(written) // 7 + 1
    recorder.write_csv(tmp_path / "series.csv")
    pd.testing.assert_frame_equal(pd.read_csv(tmp_path / "series.csv"), written, check_dtype=False)
    frame = ColumnFrame(tmp_path / "series.parquet")
    assert len(frame) == len(written) and list(frame.columns) == list(written.columns)
    np.testing.assert_array_equal(frame.iloc[3:9]["ship.x"], written["ship.x"].iloc[3:9])


def test_in_memory_and_streamed_recorders_agree(tmp_path):
    streamed = Recorder(0.0, 2.0, 40, spool=tmp_path / "spool", chunk_rows=5)
    held = Recorder(0.0, 2.0, 40)
    for _ in zip(simulate(streamed), simulate(held)):
        pass
    streamed.finish()
    held.finish()
    pd.testing.assert_frame_equal(streamed.to_frame(), held.to_frame())


def test_array_outputs_are_recorded_cell_by_cell_in_c_order_as_the_float_of_each_cell():
    """``port[i,j]`` holds ``float(value[i, j])`` whatever the array's memory order and dtype;
    a 0-d array gives ``port`` and ``port[]``."""
    arrays = {
        "plan": np.arange(12.0).reshape(3, 4).T,           # a transposed view: not C-contiguous
        "count": np.array([[2**53 + 1, -3]], dtype=np.int64),
        "flag": np.array([True, False]),
        "byte": np.array([7, 250], dtype=np.uint8),
        "single": np.array([0.1, 1e-5], dtype=np.float32),
        "cube": np.linspace(-1.0, 1.0, 24).reshape(2, 3, 4)[:, ::-1, ::2],
        "scalar": np.array(2.5),
    }
    expected = {"time_s": 0.0}
    for port, value in arrays.items():
        if value.ndim == 0:
            expected[f"arr.{port}"] = float(value)
        for index in np.ndindex(value.shape):
            expected[f"arr.{port}[{','.join(map(str, index))}]"] = float(value[index])
    recorder = Recorder(0.0, 1.0, 1)
    recorder.add("arr", 0.0, arrays)
    recorder.finish()
    frame = recorder.to_frame()
    assert list(frame.columns) == list(expected)
    assert frame.iloc[0].tolist() == list(expected.values())  # exact: the same doubles


def test_a_nan_output_is_stored_as_a_missing_value_and_a_late_column_as_nan(tmp_path):
    """As pandas wrote the parts: NaN outputs are nulls in the file; the rows before a late
    column appeared hold NaN values."""
    recorder = Recorder(0.0, 1.0, 4, spool=tmp_path / "spool", chunk_rows=2)
    for k in range(5):
        recorder.add("p", float(k), {"a": float("nan") if k == 1 else float(k), **({"b": 1.0} if k >= 2 else {})})
        recorder.advance(float(k))
    recorder.finish()
    recorder.write_parquet(tmp_path / "series.parquet")
    table = pq.read_table(tmp_path / "series.parquet")
    assert table.column("p.a").null_count == 1 and table.column("p.a").to_pylist()[1] is None
    late = table.column("p.b").to_numpy(zero_copy_only=False)
    assert table.column("p.b").null_count == 0 and np.isnan(late[:2]).all() and late[2:].tolist() == [1.0] * 3


LONG = """
[simulation]
name = "long"
steps = 3000
dt_s = 1.0
[participants.clock]
type = "python"
class = "sample_participants:Clock"
[outputs]
figures = []
"""


def test_a_run_writes_its_series_while_it_runs(write_scenario, tmp_path, monkeypatch):
    from orchestrator import master
    from orchestrator.run import run_scenario

    seen = {}
    original = master.CoSimulation.run

    def watched(self, progress=True, on_step=None, spool=None):
        def peek(k):
            if k == 2999:
                seen["parts"] = len(list(spool.glob("part-*.parquet")))
                seen["buffered"] = self.recorder.buffered_rows
        return original(self, progress=False, on_step=peek, spool=spool)

    monkeypatch.setattr(master.CoSimulation, "run", watched)
    report = run_scenario(write_scenario(LONG), tmp_path, progress=False)
    assert report.status == "finished"
    assert seen["parts"] == 3000 // 512 and seen["buffered"] == 3000 % 512
    frame = pd.read_parquet(report.folder / "timeseries.parquet")
    assert len(frame) == 3000 and frame["clock.count"].iloc[-1] == 3000.0
    assert sorted(p.name for p in report.folder.iterdir()) == ["clock_calls.csv", "summary.json",
                                                               "timeseries.parquet"]  # no spool left


def test_a_full_disk_during_the_run_is_one_line_and_leaves_nothing(write_scenario, tmp_path, capsys, monkeypatch):
    real = pq.write_table
    written = []

    def filling(table, path, *args, **kwargs):  # the writer of the spool's parts
        if len(written) == 2:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        written.append(path)
        return real(table, path, *args, **kwargs)

    monkeypatch.setattr(pq, "write_table", filling)
    code = main(["run", str(write_scenario(LONG)), "--results", str(tmp_path / "results"), "--no-progress"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 4
    assert len(err) == 1 and err[0].endswith("the time series could not be written (the disk is full)")
    assert not (tmp_path / "results").exists()


def test_a_column_frame_answers_as_the_dataframe_it_stands_for(tmp_path):
    """Analyses written against a DataFrame keep working: the usual access reads columns, any
    other attribute reads the whole series."""
    frame = pd.DataFrame({"time_s": np.arange(10.0), "ship.x": np.arange(10.0) ** 2, "ship.y": -np.arange(10.0)})
    frame.to_parquet(tmp_path / "series.parquet", index=False)
    lazy = ColumnFrame(tmp_path / "series.parquet")
    pd.testing.assert_series_equal(lazy["ship.x"], frame["ship.x"])
    pd.testing.assert_frame_equal(lazy[["ship.x", "ship.y"]], frame[["ship.x", "ship.y"]])
    pd.testing.assert_series_equal(lazy.iloc[2:7]["ship.y"], frame["ship.y"].iloc[2:7].reset_index(drop=True))
    pd.testing.assert_series_equal(lazy.iloc[3], frame.iloc[3])
    assert lazy.loc[4, "ship.x"] == 16.0 and lazy.shape == (10, 3) and len(lazy.iloc[8:]) == 2
    assert lazy.get("ship.z") is None and "ship.x" in lazy.columns
    with pytest.raises(KeyError):
        lazy["ship.z"]


def test_outputs_that_change_kind_or_order_between_steps_are_recorded_by_name_as_floats():
    """The columns of a participant's all-float outputs are named once; an output given as an
    int, a numpy number or an array at a later step, or the ports in another order, is still
    recorded under its own name as a float (cells by index)."""
    steps = [
        {"a": 1.0, "b": 2.0},
        {"a": 3, "b": np.float64(4.5)},
        {"b": 6.0, "a": 5.0},
        {"a": np.array([7.0, 8.0]), "b": 9.0},
        {"a": 10.0, "b": 11.0},
    ]
    recorder = Recorder(0.0, 1.0, len(steps))
    for k, outputs in enumerate(steps):
        recorder.add("p", float(k), outputs)
        recorder.advance(float(k))
    frame = recorder.to_frame()
    assert list(frame.columns) == ["time_s", "p.a", "p.b", "p.a[0]", "p.a[1]"]
    assert frame["p.a"].tolist() == [1.0, 3.0, 5.0, 5.0, 10.0]  # (the array's step keeps the last scalar)
    assert frame["p.b"].tolist() == [2.0, 4.5, 6.0, 9.0, 11.0]
    assert frame["p.a[1]"].iloc[3:].tolist() == [8.0, 8.0]
    assert all(type(value) is float for row in recorder._rows for value in row)


def test_times_meet_the_grid_as_rounded_to_its_decimals_whether_rounded_or_not():
    """A time that is a whole number of 64ths of a second is not rounded: it must come out as
    rounding would give it, and any other time rounded."""
    from orchestrator.recorder import TIME_DECIMALS, on_grid_decimals

    rng = np.random.default_rng(3)
    times = np.concatenate([np.arange(-50, 5000) / 64.0, rng.integers(0, 2 ** 40, 500) / 64.0, np.arange(300) / 128.0,
                            np.arange(5000) * 0.1, np.arange(5000) * 0.3 + 1e-7, rng.uniform(-1e6, 1e6, 2000),
                            [2.0 ** 60, -0.0, 1e-7, 0.0000005, 0.0000015]])
    for time_s in times.tolist() + [3, np.float64(7.25), np.float64(0.1)]:
        assert repr(on_grid_decimals(time_s)) == repr(round(float(time_s), TIME_DECIMALS)), time_s
        recorder = Recorder(0.0, 1.0, 1)
        recorder.add_floats(time_s, recorder.float_columns("p", ("a",)), (1.0,))
        assert repr(recorder.last_time()) == repr(max(0.0, round(float(time_s), TIME_DECIMALS))), time_s


def test_a_port_named_as_another_ports_cell_holds_the_later_value_in_one_column():
    """Outputs whose column names meet (a port ``a[0]`` beside an array ``a``) are recorded as a
    dict of them keeps them: one column, the value given later."""
    recorder = Recorder(0.0, 1.0, 2)
    for k in range(2):
        recorder.add("p", float(k), {"a": np.array([1.0 + k, 2.0]), "a[0]": 5.0 + k})
        recorder.advance(float(k))
    frame = recorder.to_frame()
    assert list(frame.columns) == ["time_s", "p.a[0]", "p.a[1]"]
    assert frame["p.a[0]"].tolist() == [5.0, 6.0] and frame["p.a[1]"].tolist() == [2.0, 2.0]


def test_outputs_with_arrays_are_recorded_as_given_at_every_step_as_their_shapes_change():
    """The columns of outputs with arrays are named once per set of ports and shapes: a step
    that gives other shapes, kinds or values is recorded as its own."""
    steps = [{"a": np.array([1.0, 2.0]), "b": 3.0},
             {"a": np.array([4.0, 5.0]), "b": 6},
             {"a": np.array([[7, 8, 9]], dtype=np.int32), "b": np.float32(0.5)},
             {"a": np.array([10.0, 11.0]), "b": 12.0}]
    recorder = Recorder(0.0, 1.0, len(steps))
    for k, outputs in enumerate(steps):
        recorder.add("p", float(k), outputs)
        recorder.advance(float(k))
    frame = recorder.to_frame()
    assert list(frame.columns) == ["time_s", "p.a[0]", "p.a[1]", "p.b", "p.a[0,0]", "p.a[0,1]", "p.a[0,2]"]
    assert frame["p.a[0]"].tolist() == [1.0, 4.0, 4.0, 10.0]
    assert frame["p.b"].tolist() == [3.0, 6.0, 0.5, 12.0]
    assert frame["p.a[0,2]"].tolist()[2:] == [9.0, 9.0]
    assert all(type(value) is float for row in recorder._rows for value in row)
