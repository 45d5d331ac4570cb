"""Voyage accounting: cost, CO2 and the IMO Carbon Intensity Indicator of a sailed track.

The energy model (:mod:`rhnc.ship.energy`, docs/method.md) gives the cost rate EC [USD/h] and
the emission rate EM [kg CO2/h] at each sample of the sailed trajectory from the ship's
speed through water and heading and the local weather it met.  Totals integrate them with
the trapezoid rule between samples, as the paper does for its Table 3.

Carbon Intensity Indicator (IMO MEPC.352(78), .353(78), .354(78)), applied to the voyage:

* attained CII (AER) = CO2 [g] / (capacity [dwt] x distance [nm]); for a container ship the
  capacity is the deadweight;
* reference line CII_ref = a Capacity^-c, container ships a = 1984, c = 0.489 (G2);
* required CII = (1 - Z / 100) CII_ref, with the reduction factor Z of the reporting year
  (G3: 5 % for 2023, 7 % 2024, 9 % 2025, 11 % 2026);
* rating by attained / required against the container-ship boundaries (G4)
  d1..d4 = 0.83, 0.94, 1.07, 1.19: A below d1, B below d2, C below d3, D below d4, else E.

The CII is an annual figure; applied to one passage it says how carbon-intensive that
passage would be if the whole year were sailed like it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rhnc.ship.energy import EnergyParameters, brake_power, cost_rate, emission_rate
from orchestrator.geometry import KNOT, NM

CONTAINER_CII_A = 1984.0
CONTAINER_CII_C = 0.489
CONTAINER_RATING_BOUNDARIES = (0.83, 0.94, 1.07, 1.19)
REDUCTION_FACTOR_PERCENT = {2023: 5.0, 2024: 7.0, 2025: 9.0, 2026: 11.0}


@dataclass(frozen=True)
class VoyageAccount:
    """Totals of a sailed voyage."""

    cost_usd: float
    co2_t: float
    distance_nm: float
    time_min: float
    cost_per_nm_usd: float
    co2_per_nm_kg: float
    cii_attained: float
    cii_required: float
    cii_reference: float
    cii_rating: str
    cii_year: int

    def as_dict(self) -> dict:
        return {key: (round(value, 6) if isinstance(value, float) else value)
                for key, value in self.__dict__.items()}


def cii_reference(deadweight_t: float) -> float:
    """Reference CII of a container ship [g CO2 / (dwt nm)] (MEPC.353(78))."""
    return CONTAINER_CII_A * deadweight_t ** (-CONTAINER_CII_C)


def cii_rating(attained: float, required: float) -> str:
    """A to E from attained / required against the container-ship boundaries (MEPC.354(78))."""
    ratio = attained / required
    for letter, bound in zip("ABCD", CONTAINER_RATING_BOUNDARIES):
        if ratio < bound:
            return letter
    return "E"


def rates_along_track(speed_through_water, heading, wind_north, wind_east, hs,
                      params: EnergyParameters = EnergyParameters()):
    """EC [USD/h] and EM [kg/h] at each sample of a track."""
    power = brake_power(np.maximum(speed_through_water, 0.0), heading, wind_north, wind_east, hs, params)
    return cost_rate(power, params), emission_rate(power, params)


def mean_speed_through_water_kn(time_s, surge_mps, sway_mps) -> float:
    """Time-averaged speed through water [kn] of a sailed track.

    The speed through water is the length of the ship's velocity relative to the water,
    ``hypot(u, v)`` from the plant's surge and sway; its average over time (trapezoid rule
    between samples) is the distance sailed through the water divided by the time taken.

    Parameters
    ----------
    time_s : array_like
        Sample times [s], increasing.
    surge_mps, sway_mps : array_like
        Surge u and sway v relative to the water [m/s].
    """
    t = np.asarray(time_s, dtype=float)
    speed = np.hypot(np.asarray(surge_mps, dtype=float), np.asarray(sway_mps, dtype=float))
    if t.size < 2 or t[-1] <= t[0]:
        return float(speed[0] / KNOT) if speed.size else float("nan")
    return float(np.trapezoid(speed, t) / (t[-1] - t[0]) / KNOT)


def account_voyage(time_s, x, y, speed_through_water, heading, wind_north, wind_east, hs,
                   params: EnergyParameters = EnergyParameters(), cii_year: int = 2026,
                   brake_power_w=None) -> VoyageAccount:
    """Cost, CO2, distance and CII of a sailed track.

    Parameters
    ----------
    time_s : array_like
        Sample times [s].
    x, y : array_like
        Positions north and east [m].
    speed_through_water : array_like
        Surge speed through water u [m/s].
    heading : array_like
        Heading [rad].
    wind_north, wind_east, hs : array_like
        Local weather at each sample [m/s, m/s, m].
    params : EnergyParameters
    cii_year : int
        Year whose reduction factor Z sets the required CII.
    brake_power_w : array_like, optional
        Brake power at each sample [W] when it is known (from a plant that reports the
        power delivered to its propeller); otherwise the energy model computes it from the
        speed, heading and weather.
    """
    if cii_year not in REDUCTION_FACTOR_PERCENT:
        raise ValueError(f"cii_year {cii_year}: reduction factor known for {sorted(REDUCTION_FACTOR_PERCENT)}")
    t = np.asarray(time_s, dtype=float)
    if brake_power_w is None:
        ec, em = rates_along_track(speed_through_water, heading, wind_north, wind_east, hs, params)
    else:
        power = np.maximum(np.asarray(brake_power_w, dtype=float), 0.0)
        ec, em = cost_rate(power, params), emission_rate(power, params)
    hours = t / 3600.0
    cost = float(np.trapezoid(ec, hours)) if t.size > 1 else 0.0
    co2_kg = float(np.trapezoid(em, hours)) if t.size > 1 else 0.0
    distance_nm = float(np.sum(np.hypot(np.diff(x), np.diff(y)))) / NM
    reference = cii_reference(params.deadweight_t)
    required = (1.0 - REDUCTION_FACTOR_PERCENT[cii_year] / 100.0) * reference
    attained = co2_kg * 1000.0 / (params.deadweight_t * distance_nm) if distance_nm > 0 else float("nan")
    return VoyageAccount(
        cost_usd=cost,
        co2_t=co2_kg / 1000.0,
        distance_nm=distance_nm,
        time_min=float(t[-1] - t[0]) / 60.0 if t.size else 0.0,
        cost_per_nm_usd=cost / distance_nm if distance_nm > 0 else float("nan"),
        co2_per_nm_kg=co2_kg / distance_nm if distance_nm > 0 else float("nan"),
        cii_attained=attained,
        cii_required=required,
        cii_reference=reference,
        cii_rating=cii_rating(attained, required) if distance_nm > 0 else "n/a",
        cii_year=cii_year,
    )
