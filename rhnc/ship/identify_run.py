"""``python -m orchestrator identify S.toml``: identify the NMPC's model on the scenario's plant.

Writes ``results/identify/<set>/<run-id>/`` with ``parameter_sets.toml`` (the fitted set,
ready for the control participant's ``model_file``/``model_set``), ``fit_report.json``
(coefficients, residuals, R², open-loop errors per manoeuvre and on the held-out one),
``fit_report.md`` and one figure per manoeuvre; with ``out`` also a copy of the
parameter-set file there.

A plant at actuator level (it takes rudder angle and propeller revolutions, not tau) is
identified through the scenario's ``allocation`` participant, as the NMPC sees it in a run
(:class:`AllocatedPlant`).  Before the manoeuvres a short probe
(:mod:`rhnc.ship.plant_probe`) refuses a mapping whose signs, angle convention or units
contradict the canonical frame.
"""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass
from pathlib import Path

from orchestrator.errors import ScenarioError
from orchestrator.geometry import KNOT
from orchestrator.results import RunFolder, new_run_id, versions
from orchestrator.scenario import ParticipantSpec, load_scenario
from rhnc.ship.equation_error import ALL_COEFFICIENTS, COEFFICIENTS
from rhnc.ship.identification import Horizon, check_bounds, identify_model
from rhnc.ship.sea_trials import VALIDATION_MANOEUVRE, PlantRunner
from rhnc.ship.identification_report import parameter_set_toml, write_figures
from rhnc.ship.plant_probe import probe_plant
from rhnc.ship.ship_model import STATE_NAMES, load_parameter_set

LOG = logging.getLogger(__name__)
START_PORTS = ("x", "y", "psi", "u", "v", "r")


@dataclass
class IdentifyReport:
    folder: Path
    parameter_file: Path
    report: dict


class AllocatedPlant:
    """An actuator-level plant FMU behind the scenario's allocation participant, seen from tau.

    The NMPC of such a scenario demands tau = [surge force, yaw moment] from the allocation,
    which commands the plant's rudder and propeller; so its model must be identified on the
    two together.  Each step feeds tau to the allocation (with the plant's reported speed and
    actuators, as the scenario's connections do) and its commands to the plant, at the
    identification's sampling step, so the allocation's rate limits act as in a run.

    Parameters
    ----------
    allocation : Participant
        The scenario's allocation participant (inputs ``tau_u``, ``tau_r``, ...).
    plant : FmuParticipant
        The plant FMU participant.
    commands : list of (str, str)
        Allocation output -> plant input, from the scenario's connections.
    feedback : list of (str, str)
        Plant output -> allocation input, from the scenario's connections.
    """

    def __init__(self, allocation, plant, commands, feedback) -> None:
        self.allocation = allocation
        self.plant = plant
        self.commands = list(commands)
        self.feedback = list(feedback)
        driven = {port for _, port in self.commands}
        self.input_names = tuple(port for port in plant.input_names if port not in driven) + ("tau_u", "tau_r")
        self.output_names = tuple(plant.output_names)
        self._outputs: dict = {}

    def _fed_back(self) -> dict:
        return {target: self._outputs[source] for source, target in self.feedback if source in self._outputs}

    def setup(self, start_time: float, inputs) -> dict:
        self._outputs = self.plant.setup(start_time, {k: v for k, v in inputs.items() if k in self.plant.input_names})
        self.allocation.setup(start_time, self._fed_back())
        return self._outputs

    def step(self, time: float, step_size: float, inputs) -> dict:
        demand = {"tau_u": inputs["tau_u"], "tau_r": inputs["tau_r"], **self._fed_back()}
        commands = self.allocation.step(time, step_size, demand)
        plant_inputs = {k: v for k, v in inputs.items() if k in self.plant.input_names}
        plant_inputs.update({target: commands[source] for source, target in self.commands})
        self._outputs = self.plant.step(time, step_size, plant_inputs)
        return self._outputs

    def terminate(self) -> None:
        self.allocation.terminate()
        self.plant.terminate()


def allocation_between(scenario, plant: ParticipantSpec):
    """The allocation participant driving ``plant`` and the wiring: (spec, commands, feedback) or None."""
    for spec in scenario.participants:
        if spec.type != "allocation":
            continue
        commands = [(c.source_port, c.target_port) for c in scenario.connections
                    if c.source == spec.name and c.target == plant.name]
        if commands:
            feedback = [(c.source_port, c.target_port) for c in scenario.connections
                        if c.source == plant.name and c.target == spec.name]
            return spec, commands, feedback
    return None


def find_plant_spec(scenario, name: str | None) -> ParticipantSpec:
    """The FMU participant to identify: ``name``, or the one FMU whose ports are the ship's."""
    fmus = [spec for spec in scenario.participants if spec.is_fmu]
    if name is not None:
        for spec in fmus:
            if spec.name == name:
                return spec
        raise ScenarioError(f"{scenario.path}: --plant {name}: no FMU participant of that name "
                            f"(FMU participants: {', '.join(s.name for s in fmus) or 'none'})")
    ships = [spec for spec in fmus
             if {"x", "psi"} <= (ports := set(spec.mapping) | _own_names(spec, scenario))
             and ("tau_u" in ports or allocation_between(scenario, spec) is not None)]
    if len(ships) != 1:
        raise ScenarioError(f"{scenario.path}: cannot tell the plant FMU ({len(ships)} candidates); name it with --plant")
    return ships[0]


def _build_participant(scenario, spec: ParticipantSpec):
    """A Python participant of the scenario built as a run builds it (step: the identification's sample)."""
    from orchestrator.participant_build import participant_class, participant_target
    from orchestrator.participant import BuildContext
    from rhnc.ship.sea_trials import SAMPLE_S

    where = f"{scenario.path}: participants.{spec.name}"
    context = BuildContext(where=where, scenario_dir=scenario.directory, step_size=SAMPLE_S,
                           start_time=0.0, stop_time=scenario.simulation.stop_s)
    return participant_class(participant_target(spec, where), f"{where}.type").from_options(spec.name, spec.options,
                                                                                          context)


def _own_names(spec, scenario) -> set[str]:
    """Ports an FMU has under the canonical names without a mapping (read from the FMU)."""
    from fmpy import read_model_description

    from orchestrator.fmu_participant import resolve_fmu

    path = resolve_fmu(spec.fmu, scenario.directory, f"{scenario.path}: participants.{spec.name}")
    return {v.name for v in read_model_description(str(path)).modelVariables}


def run_identify(scenario_path, results_root="results", plant: str | None = None, speed_kn: float = 18.0,
                 tau_u_max_N: float | None = None, tau_r_max_Nm: float | None = None,
                 set_name: str | None = None, out: Path | None = None, ship: str | None = None, *,
                 horizon: Horizon) -> IdentifyReport:
    """Identify the prediction model on the scenario's plant FMU and write the results.

    ``horizon``: the NMPC's prediction horizon and control interval the model is chosen for
    (:func:`rhnc.cosim.identify_horizon.nmpc_horizon` reads them from the scenario).

    ``ship`` (a name in ``ships/`` or a ship TOML file) gives the particulars that bound the
    mass matrix of the model class with the hull polynomial (:mod:`rhnc.ship.physical_bounds`).

    Raises
    ------
    ScenarioError
        Bad scenario, no unique plant, missing bounds, a plant without start parameters
        for the initial state, a mapping the probe finds against the canonical frame.
    ToolchainError
        The plant cannot be identified (see :func:`rhnc.ship.identification.identify_model`).
    """
    from orchestrator.fmu_participant import FmuParticipant, resolve_fmu

    tau_u_max, tau_r_max = check_bounds(tau_u_max_N, tau_r_max_Nm)
    masses = _ship_masses(ship)
    if not (speed_kn > 0):
        raise ScenarioError(f"identify: --speed-kn must be positive, got {speed_kn}")
    scenario = load_scenario(scenario_path)
    spec = find_plant_spec(scenario, plant)
    where = f"{scenario.path}: participants.{spec.name}"
    assert spec.fmu is not None  # find_plant_spec returns FMU participants only
    path = resolve_fmu(spec.fmu, scenario.directory, where)
    probe = FmuParticipant(spec, path, where)
    identity = probe.identity
    build, allocation = _manoeuvre_plants(scenario, spec, path, where)
    seen = build({}) if allocation is not None else probe
    missing = [port for port in (*STATE_NAMES, "tau_u", "tau_r") if port not in (*seen.output_names, *seen.input_names)]
    if missing:
        raise ScenarioError(f"{where}: identify needs the plant ports {', '.join(missing)} (map them)")
    probe_report = probe_plant(build, speed_kn * KNOT, tau_u_max, tau_r_max, where)
    name = set_name or identity["model_name"]
    kcs = load_parameter_set("default")
    fit = identify_model(PlantRunner(build, speed_kn * KNOT), tau_u_max, tau_r_max, name, reference=kcs,
                         masses=masses, horizon=horizon, bound_every_class=allocation is not None)
    source = Path(scenario_path).as_posix()
    toml_text = parameter_set_toml(fit, {**identity, "through": allocation[0].name if allocation else None}, source)
    folder = RunFolder(Path(results_root), f"identify/{name}", new_run_id(scenario.sha256))
    try:
        folder.path("parameter_sets.toml").write_text(toml_text)
        figures = write_figures(fit, folder.staging)
        plant_entry = {"participant": spec.name, "fmu": str(path), **identity,
                       "through": allocation[0].name if allocation is not None else None}
        report = _fit_report(fit, name, scenario, plant_entry, speed_kn, probe_report,
                             {"tau_u_max_N": tau_u_max, "tau_r_max_Nm": tau_r_max}, figures)
        folder.write_json("fit_report.json", report)
        folder.path("fit_report.md").write_text(_markdown(report))
        final = folder.publish()
    except BaseException:
        folder.discard()
        raise
    parameter_file = final / "parameter_sets.toml"
    if out is not None:
        out = Path(out)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(toml_text)
        parameter_file = out
    return IdentifyReport(final, parameter_file, report)


def _ship_masses(ship: str | None):
    """The mass bounds from the particulars of ``ship`` (a name in ships/ or a TOML file), or None."""
    from rhnc.ship.physical_bounds import mass_from_particulars
    from rhnc.ship.ships import load_ship

    if ship is None:
        return None
    path = Path(ship)
    if path.suffix == ".toml":
        if not path.is_file():
            raise ScenarioError(f"identify: --ship {ship}: file not found")
        return mass_from_particulars(load_ship(path.stem, path.resolve().parent))
    return mass_from_particulars(load_ship(ship))


def _manoeuvre_plants(scenario, spec, path: Path, where: str):
    """``build(initial)``: the plant for one manoeuvre (through the scenario's allocation, if
    any), without the scenario's start values; and that allocation (None without one)."""
    from orchestrator.fmu_participant import FmuParticipant

    # the manoeuvres set their own initial state: drop the scenario's start values
    starts = set()
    for port in START_PORTS:
        entry = spec.mapping.get(port)
        starts.add(getattr(entry, "start", None) or f"{port}0")
    parameters = {k: v for k, v in spec.parameters.items() if k not in starts}

    allocation = allocation_between(scenario, spec)

    def build(initial):
        manoeuvre_spec = dataclasses.replace(spec, parameters=parameters, initial=initial)
        plant = FmuParticipant(manoeuvre_spec, path, where)
        if allocation is None:
            return plant
        return AllocatedPlant(_build_participant(scenario, allocation[0]), plant, allocation[1], allocation[2])

    return build, allocation


def _fit_report(fit, set_name: str, scenario, plant_entry: dict, speed_kn: float, probe_report, bounds: dict,
                figures) -> dict:
    """``fit_report.json``: what was identified, on which plant, and how well it predicts."""
    return {
        "scenario": str(scenario.path),
        "plant": plant_entry,
        "speed_kn": speed_kn,
        "probe": probe_report,
        "trim_tau_u_N": fit.trim_tau_u,
        "set": set_name,
        "model_class": fit.model_class,
        "horizon_s": fit.horizon.horizon_s if fit.horizon else None,
        "control_interval_s": fit.horizon.interval_s if fit.horizon else None,
        "held_out_cost_per_class": fit.class_errors,
        "held_out_open_loop_cost_per_class": fit.class_open_loop_errors,
        "notes": fit.notes,
        "coefficients": {k: getattr(fit.parameters, k) for k in ALL_COEFFICIENTS
                         if k in COEFFICIENTS or getattr(fit.parameters, k) != 0.0},
        "bounds": bounds,
        "residual_rms": fit.residual_rms,
        "r_squared": fit.r_squared,
        "open_loop_errors": fit.validation,
        "held_out": VALIDATION_MANOEUVRE,
        "prediction_error": fit.prediction_error,
        "figures": figures,
        "versions": versions(),
    }


def _markdown(report: dict) -> str:
    lines = [f"# Identification of {report['set']} on {report['plant']['model_name']}", "",
             f"Plant `{report['plant']['participant']}` of `{report['scenario']}`, from {report['speed_kn']} kn, "
             f"weather off; surge force at trim {report['trim_tau_u_N']:.4g} N.", "",
             f"Model class: {report['model_class']}, chosen by the weighted error of its predictions of the held-out "
             f"manoeuvre over the NMPC's {report['horizon_s']:g}-s horizon from every {report['control_interval_s']:g} s "
             "of measured state, per class: " + ", ".join(
                 f"{k} {v:.4g}" if v is not None else f"{k} no physical fit"
                 for k, v in report["held_out_cost_per_class"].items()) + " (one open-loop run over the whole "
             "manoeuvre: " + ", ".join(f"{k} {v:.4g}" for k, v in report["held_out_open_loop_cost_per_class"].items())
             + ").", "",
             *[f"- {note}" for note in report["notes"]], "",
             "| coefficient | value |", "|---|---|"]
    lines += [f"| {k} | {v:.6g} |" for k, v in report["coefficients"].items()]
    lines += [f"| {k} | {v:.6g} |" for k, v in report["bounds"].items()]
    lines += ["", "Equation residuals (RMS) and R²: " + ", ".join(
        f"{k} {v:.4g}" for k, v in report["residual_rms"].items()) + "; " + ", ".join(
        f"{k} {v:.4f}" for k, v in report["r_squared"].items() if v is not None), "",
        "| manoeuvre (open loop) | heading RMS [deg] | heading max [deg] | speed RMS [kn] | yaw rate RMS [deg/min] | position at end [m] |",
        "|---|---|---|---|---|---|"]
    for name, e in report["open_loop_errors"].items():
        lines.append(f"| {name} | {e['heading_rms_deg']:.2f} | {e['heading_max_deg']:.2f} | {e['speed_rms_kn']:.3f} | "
                     f"{e['yaw_rate_rms_deg_min']:.2f} | {e['position_end_m']:.0f} |")
    error = report.get("prediction_error")
    if error:
        at_horizon = error[f"max_error_{int(error['horizon_s'])}s_m"]
        lines += ["", f"Position error of the model's predictions from every {error['horizon_s']:.0f}-s window's measured "
                  f"start: at most {error['max_error_20s_m']:.1f} m after 20 s, {error['max_error_60s_m']:.1f} m after "
                  f"60 s, {at_horizon:.0f} m after {error['horizon_s']:.0f} s; "
                  f"growth {error['growth_mps']:.3f} m/s ({error['growth_mps'] / KNOT:.2f} kn), the NMPC's default "
                  "clearance margin growth with this model."]
    return "\n".join(lines) + "\n"
