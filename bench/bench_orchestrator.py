"""Orchestrator overhead per macro step against a raw fmpy doStep loop on the same FMU, and where it goes.

The raw loop does what any master must do per step: set the two inputs, doStep, read the
plant's outputs, through FMPy's ``setReal``/``doStep``/``getReal``.  The orchestrator adds the
scripted helm participant, the connection lookup, the finiteness checks, the watchdog's
bookkeeping, the interrupt check and the recorder.  Goal: at most 2x the raw loop.  The same
loop on FMPy's low-level calls with arrays made once (how the FMU participant calls it) is
printed beside it.

Processor time (``time.process_time``), the configurations interleaved round by round
(the machine may be shared), medians over the rounds.  The breakdown times each part of a
master step alone, on the same participants and values, as many times as the run does:

    python bench/bench_orchestrator.py [--steps 20000] [--rounds 5]
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
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


def raw_loop(fmu_path: Path, steps: int, low_level: bool = False) -> float:
    """Processor time [s] of ``steps`` set-doStep-get rounds straight on FMPy's FMU2Slave: its
    ``setReal``/``doStep``/``getReal``, or (``low_level``) its ``fmi2SetReal``/``fmi2DoStep``/
    ``fmi2GetReal`` on value-reference and value arrays made once, as the FMU participant calls them."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave, fmi2Real, fmi2ValueReference

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
    started = time.process_time()
    if low_level:
        component, set_real, do_step, get_real = slave.component, slave.fmi2SetReal, slave.fmi2DoStep, slave.fmi2GetReal
        input_refs, input_values = (fmi2ValueReference * 2)(*inputs), (fmi2Real * 2)()
        output_refs, output_values = (fmi2ValueReference * 8)(*outputs), (fmi2Real * 8)()
        for k in range(steps):
            input_values[:] = [7.7377e5, 3.3e8 if k >= 60 else 0.0]
            set_real(component, input_refs, 2, input_values)
            do_step(component, float(k), 1.0, 1)
            get_real(component, output_refs, 8, output_values)
            output_values[:]
    else:
        for k in range(steps):
            slave.setReal(inputs, [7.7377e5, 3.3e8 if k >= 60 else 0.0])
            slave.doStep(currentCommunicationPoint=float(k), communicationStepSize=1.0)
            slave.getReal(outputs)
    elapsed = time.process_time() - started
    slave.terminate()
    slave.freeInstance()
    shutil.rmtree(unzip, ignore_errors=True)
    return elapsed


def _cosim(folder: Path, steps: int):
    from orchestrator.master import CoSimulation
    from orchestrator.scenario import load_scenario

    path = folder / "bench.toml"
    path.write_text(textwrap.dedent(SCENARIO.format(steps=steps)))
    return CoSimulation(load_scenario(path))


def orchestrated(steps: int) -> tuple[float, float, float]:
    """Processor time [s] of the master's steps (as many as the raw loop's), of the rest of its
    run (set-up: the FMU unpacked and loaded; terminate; summaries) and of assembling the time
    series after it."""
    folder = Path(tempfile.mkdtemp())
    cosim = _cosim(folder, steps + 1)
    marks: dict[int, float] = {}

    def on_step(k: int) -> None:  # the time when step k has ended
        if k in (0, steps):
            marks[k] = time.process_time()

    started = time.process_time()
    outcome = cosim.run(progress=False, on_step=on_step)
    elapsed = time.process_time() - started
    if outcome.status != "finished":
        raise RuntimeError(outcome.reason)
    stepping = marks[steps] - marks[0]  # steps 1 .. steps
    started_frame = time.process_time()
    outcome.recorder.to_frame()
    frame_time = time.process_time() - started_frame
    cosim.close()
    shutil.rmtree(folder, ignore_errors=True)
    return stepping, elapsed - stepping, frame_time


def parts(steps: int) -> dict[str, float]:
    """Processor time [s] of each part of a master step, each timed alone ``steps`` times on the
    participants and values of the run (the exchange as ``orchestrator.master._Loop._round``
    does it for Gauss-Seidel, written out here)."""
    import math

    from orchestrator import interrupts, time_limits
    from orchestrator.master import _input_reader
    from orchestrator.recorder import FLOAT, Recorder

    folder = Path(tempfile.mkdtemp())
    cosim = _cosim(folder, steps)
    helm, ship = cosim.participants
    times: dict[str, float] = {}
    out_helm = helm.setup(0.0, {})
    out_ship = ship.setup(0.0, {"tau_u": out_helm["tau_u"], "tau_r": out_helm["tau_r"]})
    try:
        started = time.process_time()
        for k in range(steps):
            ship.step(float(k), 1.0, out_helm)
        ship_step = time.process_time() - started
        write, _ = ship._input_writers[tuple(out_helm)]
        do_step, read = ship._do_step, ship._read_reals
        values = list(out_helm.values())
        started = time.process_time()
        for k in range(steps):
            write(values)
            do_step(steps + float(k), 1.0)
            read()
        times["FMU: FMPy's calls (set, doStep, get)"] = fmpy_calls = time.process_time() - started
        times["FMU participant around them"] = ship_step - fmpy_calls
        started = time.process_time()
        for k in range(steps):
            out_helm = helm.step(float(k), 1.0, {})
        times["helm participant's step"] = time.process_time() - started

        bus: dict = {}
        recorder = Recorder(0.0, 1.0, steps)
        # the helm's outputs are all read (connected), none of the ship's
        publications = {"helm": {tuple(out_helm): (tuple(("helm", port) for port in out_helm), None,
                                                   recorder.float_columns("helm", tuple(out_helm)))},
                        "ship": {tuple(out_ship): ((), (), recorder.float_columns("ship", tuple(out_ship)))}}
        started = time.process_time()
        for _ in range(steps):
            for name, outputs, checked, floats in (("helm", out_helm, False, False),
                                                   ("ship", out_ship, True, ship.outputs_are_floats)):
                ports, values = tuple(outputs), tuple(outputs.values())
                publication = publications[name].get(ports)
                if publication and (floats or set(map(type, values)) <= FLOAT) and (
                        checked or math.isfinite(sum(values))):
                    keys, read, _ = publication
                    if read is None:
                        bus.update(zip(keys, values))
                    elif read:
                        bus.update(zip(keys, [values[index] for index in read]))
        times["exchange: output checks, bus"] = time.process_time() - started

        input_ports, read_inputs = _input_reader((("tau_u", ("helm", "tau_u")), ("tau_r", ("helm", "tau_r"))))
        started = time.process_time()
        for _ in range(steps):
            dict(zip(input_ports, read_inputs(bus)))
        times["exchange: inputs from the bus"] = time.process_time() - started

        helm_columns, ship_columns = publications["helm"][tuple(out_helm)][2], publications["ship"][tuple(out_ship)][2]
        helm_values, ship_values = tuple(out_helm.values()), tuple(out_ship.values())
        started = time.process_time()
        for k in range(steps):
            recorder.add_floats(float(k), helm_columns, helm_values)
            recorder.add_floats(k + 1.0, ship_columns, ship_values)
            recorder.advance(float(k))
        times["recording: rows (add, advance)"] = time.process_time() - started

        watch = time_limits.CallWatch()
        try:
            started = time.process_time()
            for k in range(steps):
                for name in ("helm", "ship"):
                    watch.begin(name, "its step", float(k), 300.0)
                    watch.end()
                    watch.check()
            times["time limits (watchdog begin/end)"] = time.process_time() - started
        finally:
            watch.close()
        stop_requested = interrupts.stop_requested
        started = time.process_time()
        for _ in range(steps):
            if stop_requested() or stop_requested():
                raise KeyboardInterrupt
        times["interrupt checks"] = time.process_time() - started
    finally:
        helm.terminate()
        ship.terminate()
        cosim.close()
        shutil.rmtree(folder, ignore_errors=True)
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=20000)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    from orchestrator.fmu_build import ensure_built

    fmu = ensure_built("KCS")
    raw, low, loop, once, frame, breakdown = [], [], [], [], [], []
    for _ in range(args.rounds):  # interleaved: a load that comes and goes hits every configuration
        raw.append(raw_loop(fmu, args.steps))
        low.append(raw_loop(fmu, args.steps, low_level=True))
        stepping, rest, assembly = orchestrated(args.steps)
        loop.append(stepping)
        once.append(rest)
        frame.append(assembly)
        breakdown.append(parts(args.steps))
    per = 1e6 / args.steps
    med = statistics.median
    print(f"steps per run {args.steps}, rounds {args.rounds}, processor time, medians; "
          f"load average {os.getloadavg()[0]:.2f} (cores {os.cpu_count()})")
    print(f"raw fmpy loop                        {med(raw) * per:7.1f} us/step")
    print(f"raw fmpy loop, low-level calls       {med(low) * per:7.1f} us/step  (arrays made once, as the FMU "
          "participant calls FMPy)")
    ratios = [o / r for o, r in zip(loop, raw)]
    print(f"orchestrator (its steps)             {med(loop) * per:7.1f} us/step  ratio {med(ratios):4.2f}x "
          f"(rounds {min(ratios):.2f}-{max(ratios):.2f}x; goal <= 2x)")
    accounted = 0.0
    for name in breakdown[0]:
        value = med(b[name] for b in breakdown) * per
        accounted += value
        print(f"  {name:34s} {value:7.1f} us/step")
    print(f"  {'the loop itself (the rest)':34s} {med(loop) * per - accounted:7.1f} us/step")
    print(f"  + set-up, terminate, summaries     {med(once) * 1e3:7.1f} ms per run (once; the FMU unpacked and loaded)")
    print(f"  + time series assembly             {med(frame) * per:7.1f} us/step  (once, after the run)")


if __name__ == "__main__":
    main()
