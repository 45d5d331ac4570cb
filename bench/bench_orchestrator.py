"""Orchestrator overhead per macro step against a raw fmpy doStep loop on the same FMU.

The raw loop does what any master must do per step: set the two inputs, doStep, read the
plant's outputs.  The orchestrator adds the scripted helm participant, the connection
lookup, the finiteness checks and the recorder.  Goal: at most 3x the raw loop.

    python bench/bench_orchestrator.py [--steps 20000]
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import textwrap
import time
from pathlib import Path

SCENARIO = """
connections = ["helm.tau_u -> ship.tau_u", "helm.tau_r -> ship.tau_r"]
[simulation]
steps = {steps}
dt_s = 1.0
[participants.helm]
type = "scripted_tau"
[participants.helm.options]
tau_u_N = 7.7377e5
tau_r_steps = [[60.0, 3.3e8]]
[participants.ship]
fmu = "KCS"
[participants.ship.parameters]
u0 = 9.26
h_int = 1.0
"""


def raw_loop(fmu_path: Path, steps: int) -> float:
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmu_path))
    refs = {v.name: v.valueReference for v in md.modelVariables}
    unzip = extract(str(fmu_path))
    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName="raw")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.setReal([refs["u0"], refs["h_int"]], [9.26, 1.0])
    slave.exitInitializationMode()
    inputs = [refs["tau_u"], refs["tau_r"]]
    outputs = [refs[n] for n in ("x", "y", "psi", "u", "v", "r", "sog", "cog")]
    started = time.perf_counter()
    for k in range(steps):
        slave.setReal(inputs, [7.7377e5, 3.3e8 if k >= 60 else 0.0])
        slave.doStep(currentCommunicationPoint=float(k), communicationStepSize=1.0)
        slave.getReal(outputs)
    elapsed = time.perf_counter() - started
    slave.terminate()
    slave.freeInstance()
    shutil.rmtree(unzip, ignore_errors=True)
    return elapsed


def orchestrated(steps: int) -> float:
    from orchestrator.master import CoSimulation
    from orchestrator.scenario import load_scenario

    folder = Path(tempfile.mkdtemp())
    path = folder / "bench.toml"
    path.write_text(textwrap.dedent(SCENARIO.format(steps=steps)))
    cosim = CoSimulation(load_scenario(path))
    started = time.perf_counter()
    outcome = cosim.run(progress=False)
    elapsed = time.perf_counter() - started
    assert outcome.status == "finished", outcome.reason
    started_frame = time.perf_counter()
    outcome.recorder.to_frame()
    frame_time = time.perf_counter() - started_frame
    cosim.close()
    shutil.rmtree(folder, ignore_errors=True)
    return elapsed, frame_time


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=20000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    from orchestrator.fmu_build import ensure_built

    fmu = ensure_built("KCS")
    raw = min(raw_loop(fmu, args.steps) for _ in range(args.repeat))
    runs = [orchestrated(args.steps) for _ in range(args.repeat)]
    loop = min(r[0] for r in runs)
    frame = min(r[1] for r in runs)
    per = 1e6 / args.steps
    print(f"steps per run             {args.steps}")
    print(f"raw fmpy loop             {raw * per:8.1f} us/step")
    print(f"orchestrator (run loop)   {loop * per:8.1f} us/step  ratio {loop / raw:4.2f}x  (goal <= 3x)")
    print(f"  + time series assembly  {frame * per:8.1f} us/step  (once, after the run)")


if __name__ == "__main__":
    main()
