"""What ``identify`` writes besides its report: the parameter-set file and the fit figures.

The fit itself is :func:`rhnc.ship.identification.identify_model`; here the fitted set becomes a
file in the format of ``models/KCS/parameter_sets.toml`` and each manoeuvre a figure of the
plant's and the model's motions side by side.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from orchestrator.geometry import KNOT
from rhnc.ship.identification import NMPC_HORIZON_KEY, NMPC_INTERVAL_KEY, VALIDATION_MANOEUVRE, Fit
from rhnc.ship.ship_model import DYNAMICS_KEYS, WIDE_MODEL_KEYS


def parameter_set_toml(fit: Fit, identity: dict[str, str | None], source: str) -> str:
    """The fitted set as a parameter-set file (the format of ``models/KCS/parameter_sets.toml``)."""
    p = fit.parameters
    through = f" through its allocation '{identity['through']}'" if identity.get("through") else ""
    lines = [
        "# Identified by `python -m orchestrator identify` (rhnc/ship/identification.py): the NMPC's",
        "# 3-DOF prediction model fitted by least squares on the plant's manoeuvres, weather off.",
        "# units: m11, m22 kg; m33 kg m^2; d11, d22 kg/s; d23, d32 kg m/s; d33 kg m^2/s;",
        "#        tau_u_max N; tau_r_max N m (the bounds given to identify); when the wider model class",
        "#        is chosen: m23 kg m (sway-yaw mass coupling); d11q, d22q kg/m; d33q kg m^2 (quadratic damping);",
        "#        x_vv.. n_rrr: the cubic MMG hull polynomial (units in rhnc/ship/ship_model.py, HULL_POLYNOMIAL).",
        "#        damping_speed_mps m/s: the speed at which d22, d23, d32, d33 hold; they go with the surge speed.",
        "",
        f"[{p.name}]",
        f"description = \"Identified on {identity['model_name']}{through} from {source}; held-out "
        f"{VALIDATION_MANOEUVRE}: heading RMS "
        f"{fit.validation['held_out: ' + VALIDATION_MANOEUVRE]['heading_rms_deg']:.3f} deg; model class {p.extras.get('model_class', 'linear')}\"",
        f"plant_fmu = \"{identity['model_name']}\"",
        f"plant_guid = \"{identity['guid']}\"",
    ]
    lines += [f"{key} = {getattr(p, key)!r}" for key in DYNAMICS_KEYS
              if key not in WIDE_MODEL_KEYS or getattr(p, key) != 0.0]
    if "model_class" in p.extras:
        lines += ["# the model class chosen by its error on the held-out manoeuvre (rhnc/ship/identification.py)",
                  f"model_class = \"{p.extras['model_class']}\""]
    if fit.horizon is not None:
        lines += ["# s: the NMPC set-up the model class was chosen for (its prediction horizon, horizon_steps",
                  "# times the control interval, and that interval); a control participant with another",
                  "# set-up says so in its model_check",
                  f"{NMPC_HORIZON_KEY} = {float(fit.horizon.horizon_s)!r}",
                  f"{NMPC_INTERVAL_KEY} = {float(fit.horizon.interval_s)!r}"]
    if "position_error_growth_mps" in p.extras:
        lines += ["# m/s: growth of the model's position error with prediction time on the manoeuvres; the",
                  "# NMPC widens its collision domains by it unless the scenario sets clearance_margin_growth_kn",
                  f"position_error_growth_mps = {p.extras['position_error_growth_mps']!r}"]
    return "\n".join(lines) + "\n"


def write_figures(fit: Fit, folder: Path) -> list[str]:
    """Measured against predicted heading, speed and yaw rate per manoeuvre; returns file names."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    files = []
    for name, record in fit.records.items():
        predicted = fit.predictions[name]
        fig, axes = plt.subplots(4, 1, figsize=(8, 9), sharex=True)
        series = ((np.degrees(record.states[:, 2]), np.degrees(predicted[:, 2]), "heading [deg]"),
                  (record.states[:, 3] / KNOT, predicted[:, 3] / KNOT, "surge speed [kn]"),
                  (np.degrees(record.states[:, 5]) * 60, np.degrees(predicted[:, 5]) * 60, "yaw rate [deg/min]"))
        for axis, (measured, model, label) in zip(axes, series):
            axis.plot(record.t, measured, label="plant FMU")
            axis.plot(record.t, model, "--", label="identified model, open loop")
            axis.set_ylabel(label)
            axis.grid(True, alpha=0.3)
        axes[0].legend(loc="best")
        axes[3].plot(record.t, record.tau[:, 0] / fit.parameters.tau_u_max, label="tau_u / bound")
        axes[3].plot(record.t, record.tau[:, 1] / fit.parameters.tau_r_max, label="tau_r / bound")
        axes[3].set_ylabel("input")
        axes[3].set_xlabel("time [s]")
        axes[3].legend(loc="best")
        held = " (held out)" if name == VALIDATION_MANOEUVRE else ""
        axes[0].set_title(f"{name}{held}")
        fig.tight_layout()
        file = f"fit_{name}.png"
        fig.savefig(folder / file, dpi=90)
        plt.close(fig)
        files.append(file)
    return files
