"""What a run builds is frozen for the garbage collector while it steps and writes, and only then."""

from __future__ import annotations

import gc

from orchestrator import run
from orchestrator.master import CoSimulation

SCENARIO = """
[simulation]
stop_s = 10.0
dt_s = 5.0
[participants.helm]
type = "scripted_tau"
"""


def test_the_built_objects_are_frozen_while_the_run_steps_and_writes_and_not_after(write_scenario, tmp_path,
                                                                                   monkeypatch):
    seen = {}
    real_run, real_write = CoSimulation.run, run._write

    def stepping(self, *args, **kwargs):
        # the co-simulation, built before, is in no generation the collector walks
        seen["stepping"] = gc.is_tracked(self) and not any(self is o for o in gc.get_objects())
        return real_run(self, *args, **kwargs)

    def writing(scenario, cosim, *args, **kwargs):
        seen["writing"] = not any(cosim is o for o in gc.get_objects())
        return real_write(scenario, cosim, *args, **kwargs)

    monkeypatch.setattr(CoSimulation, "run", stepping)
    monkeypatch.setattr(run, "_write", writing)
    assert gc.get_freeze_count() == 0
    report = run.run_scenario(write_scenario(SCENARIO), tmp_path / "results", progress=False)
    assert report.ok
    assert seen == {"stepping": True, "writing": True}
    assert gc.get_freeze_count() == 0  # the process's collector is as it was


def test_objects_someone_else_froze_stay_frozen(write_scenario, tmp_path):
    kept = [["frozen by the caller"]]  # a list: always tracked by the collector
    gc.freeze()
    try:
        run.run_scenario(write_scenario(SCENARIO), tmp_path / "results", progress=False)
        assert gc.is_tracked(kept) and not any(kept is o for o in gc.get_objects())
    finally:
        gc.unfreeze()
