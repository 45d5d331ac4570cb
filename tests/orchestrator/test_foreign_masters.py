"""Our autonomy in other FMI masters, judged there by the scenario's own acceptance criteria.

Each system of ``scenarios/osp/`` (Experiments 2, 3a, 3b and a COLREG crossing) is exported
with ``export --osp`` and run to its end by OSP's libcosim (its own exchange order: every
simulator of a communication point at once) with libcosim's file observer; ``check`` judges
libcosim's CSV files by the criteria that travel with the system (``scenario.toml``).  The
verdicts must be those of our own master in its default order (Gauss-Seidel).

Every criterion must be met there: separation >= R + R_i, the COLREG rules, at most 10
yaw-moment sign changes per 100 solves, and Experiment 2's distance made good within 1 %
of our master's (``value`` in its file).

The second master: a Jacobi loop over the exported FMUs written with plain FMPy
(``FMU2Slave``), its results written with FMPy's ``write_csv``, one file per FMU.
"""

from __future__ import annotations

import glob
from pathlib import Path

import numpy as np
import pytest

from orchestrator.cli import main
from orchestrator.run import run_scenario

REPO = Path(__file__).resolve().parents[2]
NANO = 1_000_000_000
#: Experiment 2 in weather: without the model-error correction of the loop delay's prediction
#: libcosim made good 137.85 nm against our 139.76 (-1.37 %), outside its 1 % criterion
SYSTEMS = ("exp3b_head_on", "exp3a_static", "crossing_give_way", "exp2_rhnc")


def libcosim_run(config: Path, out: Path) -> list[str]:
    """Run an OSP system to its end with libcosim's file observer; the CSV files written."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    from orchestrator.scenario import load_scenario

    scenario = load_scenario(config.parent / "scenario.toml")
    log_output_level(CosimLogLevel.WARNING)
    execution = CosimExecution.from_osp_config_file(str(config))
    observer = CosimObserver.create_to_dir(str(out))
    assert execution.add_observer(observer)
    assert execution.simulate_until(int(round(scenario.simulation.stop_s * NANO)))
    del execution, observer  # the observer writes its files when it is released
    return sorted(glob.glob(str(out / "*.csv")))


def verdicts_of_check(files, scenario: Path, tmp_path: Path) -> dict[str, bool]:
    import json

    summary = tmp_path / "check.json"
    code = main(["check", *files, "--scenario", str(scenario), "--summary", str(summary)])
    criteria = json.loads(summary.read_text())["acceptance"]["criteria"]
    assert code == (0 if all(c["passed"] for c in criteria) else 3)
    return {c["name"]: c["passed"] for c in criteria}


@pytest.mark.slow
@pytest.mark.parametrize("name", SYSTEMS)
def test_exported_system_in_libcosim_gets_our_masters_verdicts(name, tmp_path):
    pytest.importorskip("libcosimpy")
    scenario = REPO / "scenarios" / "osp" / f"{name}.toml"
    out = tmp_path / "osp"
    assert main(["export", str(scenario), "--osp", "--out", str(out)]) == 0
    assert (out / "scenario.toml").read_text() == scenario.read_text()  # the criteria travel with it
    files = libcosim_run(out / "OspSystemStructure.xml", tmp_path / "libcosim")
    theirs = verdicts_of_check(files, out / "scenario.toml", tmp_path)

    ours = run_scenario(scenario, tmp_path / "ours", progress=False, overrides={"simulation.exchange": "gauss-seidel"})
    assert theirs == {c["name"]: c["passed"] for c in ours.summary["acceptance"]["criteria"]}, (theirs, ours.reason)
    assert all(theirs.values()), theirs  # and every criterion met there


def fmpy_jacobi_run(config: Path, stop_s: float, out: Path) -> list[str]:
    """A second FMI master: a Jacobi loop over the system's FMUs with plain FMPy.

    Every simulator due at a communication point steps from the values transferred before
    it; a simulator's outputs are transferred when its step ends (``stepSize`` of the
    system); its outputs are written every base step with FMPy's ``write_csv``.
    """
    import xml.etree.ElementTree as ET

    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    from fmpy.util import write_csv

    ns = {"osp": "http://opensimulationplatform.com/MSMI/OSPSystemStructure"}
    root = ET.parse(config).getroot()
    start = float(root.find("osp:StartTime", ns).text)
    base = float(root.find("osp:BaseStepSize", ns).text)
    slaves = {}
    for element in root.find("osp:Simulators", ns):
        name = element.get("name")
        path = str(config.parent / element.get("source"))
        description = read_model_description(path)
        refs = {v.name: v.valueReference for v in description.modelVariables}
        fmu = FMU2Slave(guid=description.guid, unzipDirectory=extract(path),
                        modelIdentifier=description.coSimulation.modelIdentifier, instanceName=name)
        fmu.instantiate()
        fmu.setupExperiment(startTime=start)
        fmu.enterInitializationMode()
        for initial in element.findall("osp:InitialValues/osp:InitialValue", ns):
            value = initial[0]
            kind = value.tag.split("}")[1]
            reference, text = [refs[initial.get("variable")]], value.get("value")
            if kind == "Real":
                fmu.setReal(reference, [float(text)])
            elif kind == "String":
                fmu.setString(reference, [text])
            else:
                fmu.setBoolean(reference, [text == "true"])
        every = int(round(float(element.get("stepSize")) / base))
        outputs = [v.name for v in description.modelVariables if v.causality == "output"]
        slaves[name] = {"fmu": fmu, "refs": refs, "every": every, "outputs": outputs}
    connections = [tuple((v.get("simulator"), v.get("name")) for v in pair)
                   for pair in root.find("osp:Connections", ns)]
    for slave in slaves.values():
        slave["fmu"].exitInitializationMode()

    def transfer(source: str) -> None:
        for (src, out_name), (dst, in_name) in connections:
            if src == source:
                value = slaves[src]["fmu"].getReal([slaves[src]["refs"][out_name]])
                slaves[dst]["fmu"].setReal([slaves[dst]["refs"][in_name]], value)

    def sample(time: float) -> None:
        for slave in slaves.values():
            slave.setdefault("rows", []).append(
                (time, *slave["fmu"].getReal([slave["refs"][n] for n in slave["outputs"]])))

    for name in slaves:
        transfer(name)
    sample(start)
    steps = int(round((stop_s - start) / base))
    pending: list[tuple[int, str]] = []
    for k in range(steps):
        t = start + k * base
        for name, slave in slaves.items():
            if k % slave["every"] == 0:
                h = min(slave["every"], steps - k) * base
                slave["fmu"].doStep(currentCommunicationPoint=t, communicationStepSize=h)
                pending.append((k + slave["every"], name))
        for name in [n for due, n in pending if due == k + 1]:
            transfer(name)
        pending = [(due, n) for due, n in pending if due > k + 1]
        sample(t + base)
    files = []
    for name, slave in slaves.items():
        slave["fmu"].terminate()
        slave["fmu"].freeInstance()
        result = np.array(slave["rows"], dtype=[("time", float)] + [(n, float) for n in slave["outputs"]])
        write_csv(out / f"{name}.csv", result)
        files.append(str(out / f"{name}.csv"))
    return files


@pytest.mark.slow
def test_exported_head_on_in_a_plain_fmpy_jacobi_master_gets_our_masters_verdicts(tmp_path):
    """The second master; the same verdicts and, being Jacobi, the trajectory libcosim gives."""
    from orchestrator.scenario import load_scenario

    scenario = REPO / "scenarios" / "osp" / "exp3b_head_on.toml"
    out = tmp_path / "osp"
    assert main(["export", str(scenario), "--osp", "--out", str(out)]) == 0
    csv_dir = tmp_path / "fmpy"
    csv_dir.mkdir()
    files = fmpy_jacobi_run(out / "OspSystemStructure.xml", load_scenario(scenario).simulation.stop_s, csv_dir)
    theirs = verdicts_of_check(files, out / "scenario.toml", tmp_path)
    ours = run_scenario(scenario, tmp_path / "ours", progress=False, overrides={"simulation.exchange": "gauss-seidel"})
    assert theirs == {c["name"]: c["passed"] for c in ours.summary["acceptance"]["criteria"]}
    assert all(theirs.values()), theirs
