"""The options of the ``control`` participant: the NMPC's prediction model and settings.

Every option of ``[participants.<name>.options]`` of a ``type = "control"`` participant is
checked here (errors name the scenario file, the participant and the key) and turned into
the prediction model (a parameter set of the KCS file, or an identified one of
``model_file``) and the :class:`rhnc.control.nmpc.NMPCSettings`; the participant itself
(:mod:`rhnc.control.control_participant`) runs the controller in the co-simulation.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any, overload

from orchestrator.errors import ScenarioError
from orchestrator.geometry import KNOT, NM
from orchestrator.participant import BuildContext, is_finite_number, reject_unknown_options
from rhnc.control.nmpc import SOLVERS, NMPCSettings
from rhnc.ship.identification import recorded_horizon
from rhnc.ship.ship_model import PARAMETER_SETS_FILE, available_parameter_sets, load_parameter_set

OPTIONS = (
    "parameter_set",
    "model_file",
    "model_set",
    "parameter_overrides",
    "horizon_steps",
    "control_interval_s",
    "substeps",
    "own_radius_nm",
    "solver",
    "max_iterations",
    "iteration_budget",
    "max_obstacles",
    "weights",
    "length_scale_m",
    "speed_scale_mps",
    "et_default",
    "collision_slack_weight",
    "wall_time_limit_s",
    "cpu_time_limit_s",
    "max_speed_kn",
    "colregs",
    "clearance_margin_nm",
    "clearance_margin_growth_kn",
    "stand_on_action_tcpa_s",
    "stand_on_action_range_factor",
    "apparent_alteration_deg",
    "give_way_action_tcpa_s",
    "disturbance_observer",
    "observer_gain",
    "codegen",
    "warm_start_duals",
    "real_time_iterations",
    "loop_delay_s",
    "obstacle_age_s",
    "actuators_ship",
    "chart",
    "coastline_slots",
    "reachable_reference",
)
WEIGHT_KEYS = ("q", "r", "r_rate")
#: Largest values of the integer options: bounds on the size of the NLP built from them
#: (checked before it is built; the shipped scenarios use 15-120 intervals).
INTEGER_LIMITS = {"horizon_steps": 400, "substeps": 50, "max_iterations": 100_000, "iteration_budget": 100_000,
                  "max_obstacles": 64, "coastline_slots": 64}
#: Smallest surge force of the actuators ``actuators_ship`` declares [N]: the allocation turns
#: the propeller ahead only (rhnc/control/allocation.py), so there is no astern thrust
AHEAD_ONLY_SURGE_FORCE_N = 0.0
#: Coastline slots with a chart when the options do not say (rhnc/control/nmpc_coastline.py)
DEFAULT_COASTLINE_SLOTS = 6



def controller_from_options(options: Mapping[str, Any], context: BuildContext):
    """The prediction model, NMPC settings and default event-trigger flag of the options.

    Returns
    -------
    params : rhnc.ship.ship_model.ShipParameters
        The prediction model.
    settings : NMPCSettings
    et_default : float
        Value of the ``et`` input until one is connected.
    delays : tuple of float
        ``loop_delay_s``, time from a step to its input acting on the plant [s]: the option,
        else the master's (``context.output_delay_s``: 0 in Gauss-Seidel order, one step in
        Jacobi); ``obstacle_age_s``, age of the ``obstacles`` input [s]: the option, else
        the master's (``context.input_ages_s``).

    Raises
    ------
    ScenarioError
        Naming the participant and the option.
    """
    where = context.where
    reject_unknown_options(options, OPTIONS, where)
    overrides = options.get("parameter_overrides", {})
    if not isinstance(overrides, Mapping):
        raise ScenarioError(f"{where}: option 'parameter_overrides' must be a table")
    params = _prediction_model(options, overrides, context)
    kwargs = _numeric_settings(options, context)
    if "chart" in options:
        kwargs.setdefault("coastline_slots", DEFAULT_COASTLINE_SLOTS)
    elif "coastline_slots" in options:
        raise ScenarioError(f"{where}: option 'coastline_slots' needs option 'chart' (the land to keep clear of)")
    kwargs.update(_identified_margin_growth(options, params, where))
    kwargs.update(_slack_and_weights(options, where))
    if "actuators_ship" in options:
        kwargs["tau_rate_max"] = _tau_rate_limits(options, kwargs, context)
        kwargs["tau_u_min_N"] = AHEAD_ONLY_SURGE_FORCE_N
    try:
        settings = NMPCSettings(**kwargs)
    except ValueError as error:
        raise ScenarioError(f"{where}: {error}") from None
    et_default = _number(options, "et_default", where, 0.0)
    return params, settings, et_default, _delays(options, context)


def prediction_horizon(options: Mapping[str, Any], context: BuildContext) -> tuple[int, float]:
    """The NMPC's horizon these options give: (``horizon_steps``, control interval [s]), checked
    as the participant checks them (the model ``identify`` fits is chosen for this horizon)."""
    kwargs = _numeric_settings(options, context)
    interval = kwargs["control_interval_s"]
    if not interval > 0.0:
        raise ScenarioError(f"{context.where}: option 'control_interval_s' must be > 0, got {interval!r}")
    return int(kwargs.get("horizon_steps", NMPCSettings.horizon_steps)), float(interval)


def chart_from_options(options: Mapping[str, Any], context: BuildContext):
    """The option ``chart``: land and no-go areas the NMPC keeps its clearance from (None without it)."""
    if "chart" not in options:
        return None
    from rhnc.chart.chart import load_chart

    if not isinstance(options["chart"], str) or not options["chart"]:
        raise ScenarioError(f"{context.where}: option 'chart' must be the path of a chart file, "
                            f"got {options['chart']!r}")
    try:
        return load_chart(Path(context.scenario_dir) / options["chart"])
    except ScenarioError as error:
        raise ScenarioError(f"{context.where}: option 'chart': {error}") from None


def _numeric_settings(options: Mapping[str, Any], context: BuildContext) -> dict[str, Any]:
    """NMPC settings read straight from options: interval, sizes, solver, scales, limits, flags."""
    where = context.where
    kwargs: dict[str, Any] = {
        "control_interval_s": _number(options, "control_interval_s", where, context.step_size),
        "own_radius_m": _number(options, "own_radius_nm", where, 0.0) * NM,
    }
    for key, most in INTEGER_LIMITS.items():
        if key in options:
            value = options[key]
            if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= most:
                raise ScenarioError(f"{where}: option '{key}' must be an integer from 1 to {most}, "
                                    f"got {value!r}"[:300])
            kwargs[key] = value
    if "solver" in options:
        if options["solver"] not in SOLVERS:
            raise ScenarioError(f"{where}: option 'solver' must be one of {', '.join(SOLVERS)}, got {options['solver']!r}")
        kwargs["solver"] = options["solver"]
    for key in ("length_scale_m", "speed_scale_mps"):
        if key in options:
            kwargs[key] = _number(options, key, where, None)
    for key in ("cpu_time_limit_s", "wall_time_limit_s"):  # false: no such limit
        if key in options:
            kwargs[key] = None if options[key] is False else _number(options, key, where, None)
    if "max_speed_kn" in options:
        kwargs["max_speed_mps"] = _number(options, "max_speed_kn", where, None) * KNOT
    for key in ("colregs", "disturbance_observer", "codegen", "warm_start_duals", "real_time_iterations",
                "reachable_reference"):
        if key in options:
            if not isinstance(options[key], bool):
                raise ScenarioError(f"{where}: option '{key}' must be true or false, got {options[key]!r}")
            kwargs[key] = options[key]
    for key, target, scale in (("clearance_margin_nm", "clearance_margin_m", NM),
                               ("clearance_margin_growth_kn", "clearance_margin_growth_mps", KNOT),
                               ("stand_on_action_tcpa_s", "stand_on_action_tcpa_s", 1.0),
                               ("stand_on_action_range_factor", "stand_on_action_range_factor", 1.0),
                               ("apparent_alteration_deg", "apparent_alteration_deg", 1.0),
                               ("give_way_action_tcpa_s", "give_way_action_tcpa_s", 1.0),
                               ("observer_gain", "observer_gain", 1.0)):
        if key in options:
            kwargs[target] = _number(options, key, where, None) * scale
    return kwargs


def _identified_margin_growth(options: Mapping[str, Any], params, where: str) -> dict[str, Any]:
    """The clearance margin's growth an identified model carries, unless the options set one."""
    if "clearance_margin_growth_kn" not in options and "position_error_growth_mps" in params.extras:
        # an identified model carries how fast its predicted position drifts from the
        # plant's: the collision domains are tightened by it (see rhnc/ship/identification.py)
        growth = params.extras["position_error_growth_mps"]
        if not is_finite_number(growth) or growth < 0.0:
            raise ScenarioError(f"{where}: model set '{params.name}': 'position_error_growth_mps' must be a "
                                f"number >= 0, got {growth!r}")
        return {"clearance_margin_growth_mps": float(growth)}
    return {}


def _slack_and_weights(options: Mapping[str, Any], where: str) -> dict[str, Any]:
    """``collision_slack_weight`` and the ``weights`` table's cost weights."""
    kwargs: dict[str, Any] = {}
    if "collision_slack_weight" in options:  # false: hard collision constraints
        value = options["collision_slack_weight"]
        kwargs["collision_slack_weight"] = None if value is False else _number(
            options, "collision_slack_weight", where, None)
    weights = options.get("weights", {})
    if not isinstance(weights, Mapping):
        raise ScenarioError(f"{where}: option 'weights' must be a table with keys {', '.join(WEIGHT_KEYS)}")
    reject_unknown_options(weights, WEIGHT_KEYS, f"{where}.weights")
    for key, size in zip(WEIGHT_KEYS, (6, 2, 2)):
        if key in weights:
            values = weights[key]
            if not isinstance(values, list) or len(values) != size or not all(
                is_finite_number(v) and v >= 0 for v in values
            ):
                raise ScenarioError(f"{where}.weights: '{key}' must be a list of {size} finite numbers >= 0")
            kwargs[key] = tuple(float(v) for v in values)
    return kwargs


def _tau_rate_limits(options: Mapping[str, Any], kwargs: Mapping[str, Any], context: BuildContext):
    """Rate limits of the planned tau from the steering gear and shaft of ``actuators_ship``."""
    where = context.where
    # the steering gear's and the shaft's rates bound how fast the planned tau may change
    from rhnc.control.allocation import coefficients_from_ship, tau_rate_limits

    ship = options["actuators_ship"]
    if not isinstance(ship, str) or not ship:
        raise ScenarioError(f"{where}: option 'actuators_ship' must be a ship name or a ship file path")
    speed = kwargs.get("max_speed_mps", NMPCSettings.max_speed_mps)
    return tau_rate_limits(coefficients_from_ship(ship, where, context.scenario_dir), speed)


def _delays(options: Mapping[str, Any], context: BuildContext) -> tuple[float, ...]:
    """``loop_delay_s`` and ``obstacle_age_s``: the options, else the master's."""
    where = context.where
    defaults = {"loop_delay_s": float(getattr(context, "output_delay_s", 0.0)),
                "obstacle_age_s": float(getattr(context, "input_ages_s", {}).get("obstacles", 0.0))}
    delays = []
    for key, default in defaults.items():
        value = _number(options, key, where, default)
        if value < 0.0:
            raise ScenarioError(f"{where}: option '{key}' must be a number of seconds >= 0, got {value!r}")
        delays.append(value)
    return tuple(delays)


def _prediction_model(options: Mapping[str, Any], overrides: Mapping[str, Any], context: BuildContext):
    """The NMPC's model: ``parameter_set`` of the KCS file, or ``model_set`` of ``model_file``."""
    where = context.where
    if "model_file" in options:
        if "parameter_set" in options:
            raise ScenarioError(f"{where}: give either option 'parameter_set' or 'model_file', not both")
        file = options["model_file"]
        if not isinstance(file, str) or not file:
            raise ScenarioError(f"{where}: option 'model_file' must be a path to a parameter-set TOML file")
        path = Path(file) if Path(file).is_absolute() else Path(context.scenario_dir) / file
        if not path.is_file():
            raise ScenarioError(f"{where}: option 'model_file': {path} not found "
                                "(write one with python -m orchestrator identify)")
        set_name = options.get("model_set")
        if set_name is None:
            sets = available_parameter_sets(path)
            if len(sets) != 1:
                raise ScenarioError(f"{where}: option 'model_set' must name one of {', '.join(sets)} in {path}")
            set_name = next(iter(sets))
    else:
        if "model_set" in options:
            raise ScenarioError(f"{where}: option 'model_set' needs 'model_file'")
        path = PARAMETER_SETS_FILE
        set_name = options.get("parameter_set", "default")
    if not isinstance(set_name, str):
        raise ScenarioError(f"{where}: option '{'model_set' if 'model_file' in options else 'parameter_set'}' "
                            "must be a string")
    try:
        params = load_parameter_set(set_name, overrides, path=path)
    except ScenarioError as error:
        raise ScenarioError(f"{where}: {error}") from None
    recorded_horizon(params.extras, f"{where}: {path} [{set_name}]")   # a set-up record that is no horizon
    return params


@overload
def _number(options: Mapping[str, Any], key: str, where: str, default: float) -> float: ...
@overload
def _number(options: Mapping[str, Any], key: str, where: str, default: None) -> float | None: ...
def _number(options: Mapping[str, Any], key: str, where: str, default: float | None) -> float | None:
    if key not in options:
        return default
    value = options[key]
    if not is_finite_number(value):
        raise ScenarioError(f"{where}: option '{key}' must be a finite number, got {value!r}")
    return float(value)
