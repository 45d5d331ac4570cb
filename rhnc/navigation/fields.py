"""Cost, emission and guidance fields and their superposition on the planning grid (Eq. 2-6).

The planner works on a regular grid at planning resolution (default 1 nm), resampled
bilinearly from the scenario's met-ocean grid.  On it:

* EC and EM (Eq. 2, 3) are the cost and emission *rates* [USD/h, kg/h] of the ship at
  planning speed over ground ``v`` heading from each node along the bearing towards the
  goal (the direction a ship at that node would sail; the paper does not say which
  heading its fields assume).  At the goal node itself the heading is taken as north.
* The guidance field (Eq. 4) is ``G(p) = eps |p - goal| / v exp(Delta^2 / (2 c^2))``
  with Delta = psi - phi(p) wrapped to (-pi, pi], psi the bearing from the ship (the
  planning start) to the goal and phi(p) the bearing from p to the goal.  G is a time
  [s] scaled by eps.  Eq. 5 makes eps irrelevant to the planner; c [rad] sets how
  sharply G penalises points off the ship-goal line (default 1 rad: a point abeam of
  the line costs exp(pi^2/8) = 3.4 times its on-line value).
* Each field is normalised over the map (Eq. 5); a constant field normalises to 0.
* The superposition is U = k1 EC_bar + k2 EM_bar + k3 G_bar (Eq. 6, default 1, 1, 16);
  in the collision-avoidance state the planner descends G_bar alone.

Note: EC is affine and EM linear in the brake power P (Eq. 2, 3), so after Eq. 5
EC_bar and EM_bar are the same field (P_bar).  Adding the emission field (k2 = 1) is
therefore the same as doubling the energy weight against k3; it cannot trade cost
against emission.  A differing emission field would need, e.g., a speed-dependent SFC.

EC and EM depend on the goal and the speed only, so :class:`SuperpositionField` keeps
them until the speed changes; G is rebuilt at every planning instant from the current
start point (receding horizon).  G is computed in float32 over the grid (only its
minimum and maximum are needed map-wide); U and its gradient are evaluated on the few
nodes around each path point, with exactly the values ``np.gradient`` of the full U
would give there.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from orchestrator.geometry import wrap_angle

from rhnc.ship.energy import EnergyParameters, cost_rate, emission_rate, brake_power, speed_through_water
from rhnc.weather.metocean_grid import axis_node_count, data_extent
from rhnc.weather.metocean import bilinear
from orchestrator.geometry import NM

WEATHER_NAMES = ("wind_north", "wind_east", "hs", "current_north", "current_east")


@dataclasses.dataclass(frozen=True)
class GuidanceParameters:
    """Constants of the guidance field (Eq. 4).

    Attributes
    ----------
    eps : float
        Scale epsilon (dimensionless); cancels in the normalisation (Eq. 5).
    c_rad : float
        Angular width c [rad].
    """

    eps: float = 1.0
    c_rad: float = 1.0


@dataclasses.dataclass(frozen=True)
class FieldWeights:
    """Weights of Eq. 6 (paper Table 2: k1 = k2 = 1, k3 = 16; cost-only planning: k2 = 0)."""

    k1: float = 1.0
    k2: float = 1.0
    k3: float = 16.0


@dataclasses.dataclass(frozen=True)
class PlanningWeather:
    """Met-ocean quantities on the planning grid: node axes ``x`` (north), ``y`` (east) [m]
    and (nx, ny) arrays ``wind_north``, ``wind_east`` [m/s, towards], ``hs`` [m],
    ``current_north``, ``current_east`` [m/s]."""

    x: np.ndarray
    y: np.ndarray
    wind_north: np.ndarray
    wind_east: np.ndarray
    hs: np.ndarray
    current_north: np.ndarray
    current_east: np.ndarray

    @property
    def spacing(self) -> tuple[float, float]:
        """Node spacing (dx, dy) [m]."""
        return float(self.x[1] - self.x[0]), float(self.y[1] - self.y[0])

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(x_min, x_max, y_min, y_max) [m]."""
        return float(self.x[0]), float(self.x[-1]), float(self.y[0]), float(self.y[-1])


def resample_weather(metocean, resolution_nm: float = 1.0, t_s: float | None = None) -> PlanningWeather:
    """Sample a :class:`rhnc.weather.metocean.MetOceanField` bilinearly onto a planning grid.

    Parameters
    ----------
    metocean : MetOceanField
        Anything with axes ``x``, ``y`` [m] and ``sample(x, y, t_s) -> dict``.
    resolution_nm : float
        Node spacing of the planning grid [nm].  The grid starts at the met-ocean grid's
        south-west node and stops at the last node inside its extent: the extent of its
        data (``data_extent``), without a band of held edge values around it, which is there
        so that a ship may sail over it, not to be planned on (a map grown by it changes the
        normalised fields of Eq. 5 and so the route).
    t_s : float, optional
        Time [s, simulation clock] at which a time-varying field is taken (linear between
        its time steps; the two steps are combined first, then resampled in space, which
        equals sampling at ``t_s`` to rounding); a static field ignores it.
    """
    if resolution_nm <= 0:
        raise ValueError("planning resolution must be positive")
    step = resolution_nm * NM
    x_min, x_max, y_min, y_max = data_extent(metocean)
    axis_node_count(float(x_max - x_min), step, "the planning resolution_nm")  # before allocating
    axis_node_count(float(y_max - y_min), step, "the planning resolution_nm")
    x = np.arange(x_min, x_max + 1e-6, step)
    y = np.arange(y_min, y_max + 1e-6, step)
    if x.size < 2 or y.size < 2:
        raise ValueError(f"planning resolution {resolution_nm} nm leaves fewer than 2 nodes on the map")
    xx, yy = np.meshgrid(x, y, indexing="ij")
    if getattr(metocean, "is_time_varying", False) and t_s is not None:
        metocean = metocean.snapshot(t_s)  # one spatial pass instead of one per time step
    sampled = metocean.sample(xx, yy, t_s=t_s)
    return PlanningWeather(x=x, y=y, **{name: np.asarray(sampled[name], dtype=float) for name in WEATHER_NAMES})


def bearing(from_x, from_y, to_x, to_y):
    """Bearing [rad, clockwise from north, in (-pi, pi]] from one point to another."""
    return np.arctan2(np.asarray(to_y) - from_y, np.asarray(to_x) - from_x)


def energy_rate_fields(weather: PlanningWeather, goal: Sequence[float], speed: float,
                       params: EnergyParameters = EnergyParameters()) -> tuple[np.ndarray, np.ndarray]:
    """EC [USD/h] and EM [kg/h] fields for a ship at ``speed`` over ground heading to the goal.

    Parameters
    ----------
    weather : PlanningWeather
    goal : (float, float)
        Goal (x north, y east) [m].
    speed : float
        Speed over ground [m/s]; the speed through water at each node subtracts the
        current along the heading.
    params : EnergyParameters
    """
    heading = bearing(weather.x[:, None], weather.y[None, :], goal[0], goal[1])
    stw = speed_through_water(speed, heading, weather.current_north, weather.current_east)
    power = brake_power(stw, heading, weather.wind_north, weather.wind_east, weather.hs, params)
    return cost_rate(power, params), emission_rate(power, params)


def guidance_field(x, y, start: Sequence[float], goal: Sequence[float], speed: float,
                   guidance: GuidanceParameters = GuidanceParameters()) -> np.ndarray:
    """Guidance field G [s] (Eq. 4) on the grid with node axes ``x``, ``y`` [m].

    The bearing difference is wrapped to (-pi, pi].  A start at the goal gives psi = 0.
    """
    x = np.asarray(x, dtype=float)[:, None]
    y = np.asarray(y, dtype=float)[None, :]
    distance = np.hypot(goal[0] - x, goal[1] - y)
    psi = float(bearing(start[0], start[1], goal[0], goal[1]))
    delta = wrap_angle(psi - bearing(x, y, goal[0], goal[1]))
    return guidance.eps * distance / speed * np.exp(delta ** 2 / (2.0 * guidance.c_rad ** 2))


def normalise(field: np.ndarray) -> np.ndarray:
    """Eq. 5: (F - F_min) / (F_max - F_min) over the map; a constant field gives zeros."""
    field = np.asarray(field)
    low = field.min()
    span = field.max() - low
    if not span > 1e-12 * max(abs(float(low)), 1.0):
        return np.zeros_like(field)
    return (field - low) / span


class SuperpositionField:
    """The superposed potential U (Eq. 6) for one goal, rebuilt per planning instant.

    Parameters
    ----------
    weather : PlanningWeather
    goal : (float, float)
        Goal (x north, y east) [m].
    energy : EnergyParameters
    guidance : GuidanceParameters
    weights : FieldWeights

    Call :meth:`update` with the start point and speed before sampling.
    """

    def __init__(self, weather: PlanningWeather, goal: Sequence[float],
                 energy: EnergyParameters = EnergyParameters(),
                 guidance: GuidanceParameters = GuidanceParameters(),
                 weights: FieldWeights = FieldWeights()) -> None:
        self.weather = weather
        self.goal = (float(goal[0]), float(goal[1]))
        self.energy = energy
        self.guidance = guidance
        self.weights = weights
        self.dx, self.dy = weather.spacing
        self.shape = (weather.x.size, weather.y.size)
        x = weather.x[:, None]
        y = weather.y[None, :]
        # Goal-relative geometry, fixed for the goal: distance and bearing to the goal.
        self._distance = np.hypot(self.goal[0] - x, self.goal[1] - y).astype(np.float32)
        self._bearing_to_goal = np.arctan2(self.goal[1] - y, self.goal[0] - x).astype(np.float32)
        # built by update(): None until then
        self._speed: float | None = None
        self._start: tuple[float, float] | None = None
        self.ec: np.ndarray | None = None
        self.em: np.ndarray | None = None
        self._ec_bar: np.ndarray | None = None
        self._em_bar: np.ndarray | None = None
        self._energy_bar: np.ndarray | None = None
        self._guidance: np.ndarray | None = None
        self._g_min = self._g_span = 0.0

    # -- rebuilding -------------------------------------------------------------------
    def set_weather(self, weather: PlanningWeather) -> None:
        """Replace the weather (same planning grid); EC and EM are rebuilt at the next update."""
        if (weather.x.size, weather.y.size) != self.shape:
            raise ValueError(f"new planning weather has {weather.x.size} x {weather.y.size} nodes, "
                             f"the field {self.shape[0]} x {self.shape[1]}")
        self.weather = weather
        self._speed = None

    def update(self, start: Sequence[float], speed: float) -> None:
        """Rebuild the fields for a planning start ``start`` (x, y) [m] and ``speed`` [m/s]."""
        if not speed > 0:
            raise ValueError(f"planning speed must be positive, got {speed}")
        if self._speed != speed:
            self.ec, self.em = energy_rate_fields(self.weather, self.goal, speed, self.energy)
            self._ec_bar = normalise(self.ec)
            self._em_bar = normalise(self.em)
            self._energy_bar = self.weights.k1 * self._ec_bar + self.weights.k2 * self._em_bar
            self._speed = speed
        self._start = (float(start[0]), float(start[1]))
        psi = np.float32(bearing(self._start[0], self._start[1], self.goal[0], self.goal[1]))
        # |psi - phi| wrapped into [0, pi] without a modulo: both angles lie in (-pi, pi].
        delta = np.abs(self._bearing_to_goal - psi)
        delta = np.minimum(delta, np.float32(2.0 * np.pi) - delta)
        delta *= delta
        delta *= np.float32(1.0 / (2.0 * self.guidance.c_rad ** 2))
        guidance = np.exp(delta, out=delta)
        guidance *= self._distance
        guidance *= np.float32(self.guidance.eps / speed)
        self._guidance = guidance
        self._g_min = float(guidance.min())
        span = float(guidance.max()) - self._g_min
        self._g_span = span if span > 1e-12 * max(abs(self._g_min), 1.0) else np.inf

    @property
    def speed(self) -> float | None:
        """Planning speed over ground [m/s] of the last update (None before the first)."""
        return self._speed

    def _built(self) -> tuple[np.ndarray, np.ndarray]:
        """``(E_bar, G)`` of the last update: the energy part of U and the guidance field [s]."""
        if self._energy_bar is None or self._guidance is None:
            raise RuntimeError("the fields are built by update(start, speed) first")
        return self._energy_bar, self._guidance

    @property
    def extent(self) -> tuple[float, float, float, float]:
        return self.weather.extent

    # -- whole-map views (plots, tests) ----------------------------------------------
    def guidance_s(self) -> np.ndarray:
        """G [s] of the last update (float32).

        (Not ``guidance()``: the instance attribute ``guidance``, the field's
        :class:`GuidanceParameters`, would hide a method of that name.)
        """
        return self._built()[1]

    def guidance_normalised(self) -> np.ndarray:
        """G_bar (Eq. 5) of the last update."""
        return (self._built()[1].astype(float) - self._g_min) / self._g_span

    def potential(self, avoidance: bool = False) -> np.ndarray:
        """U over the whole map (Eq. 6); G_bar alone when ``avoidance``."""
        g_bar = self.guidance_normalised()
        return g_bar if avoidance else self._built()[0] + self.weights.k3 * g_bar

    # -- local evaluation -------------------------------------------------------------
    def _patch(self, rows: slice, cols: slice, avoidance: bool) -> np.ndarray:
        energy_bar, guidance = self._built()
        g_bar = (guidance[rows, cols].astype(float) - self._g_min) / self._g_span
        if avoidance:
            return g_bar
        return energy_bar[rows, cols] + self.weights.k3 * g_bar

    def _cell(self, x: float, y: float) -> tuple[int, int, float, float]:
        nx, ny = self.shape
        fx = min(max((x - self.weather.x[0]) / self.dx, 0.0), nx - 1.0)
        fy = min(max((y - self.weather.y[0]) / self.dy, 0.0), ny - 1.0)
        i = min(int(fx), nx - 2)
        j = min(int(fy), ny - 2)
        return i, j, fx - i, fy - j

    def gradient_at(self, x: float, y: float, avoidance: bool = False) -> tuple[float, float]:
        """Gradient (dU/dx, dU/dy) [1/m] at (x, y), bilinear between node gradients.

        Node gradients are those of ``np.gradient(U, dx, dy)`` (central inside, one-sided
        on the border); points outside the map are evaluated at the nearest border point.
        """
        nx, ny = self.shape
        i, j, tx, ty = self._cell(x, y)
        r0, r1 = max(i - 1, 0), min(i + 3, nx)
        c0, c1 = max(j - 1, 0), min(j + 3, ny)
        u = self._patch(slice(r0, r1), slice(c0, c1), avoidance)
        gx = np.empty((2, 2))
        gy = np.empty((2, 2))
        for a in range(2):
            row = i + a
            lo, hi = max(row - 1, 0), min(row + 1, nx - 1)
            for b in range(2):
                col = j + b
                gx[a, b] = (u[hi - r0, col - c0] - u[lo - r0, col - c0]) / ((hi - lo) * self.dx)
                left, right = max(col - 1, 0), min(col + 1, ny - 1)
                gy[a, b] = (u[row - r0, right - c0] - u[row - r0, left - c0]) / ((right - left) * self.dy)
        weights = np.array([[(1 - tx) * (1 - ty), (1 - tx) * ty], [tx * (1 - ty), tx * ty]])
        return float((weights * gx).sum()), float((weights * gy).sum())

    def sample(self, field: np.ndarray, x, y) -> np.ndarray:
        """Bilinear value of a whole-map ``field`` (nx, ny) at points (x, y) [m], clamped to the map."""
        nx, ny = self.shape
        fx = np.clip((np.asarray(x, dtype=float) - self.weather.x[0]) / self.dx, 0.0, nx - 1.0)
        fy = np.clip((np.asarray(y, dtype=float) - self.weather.y[0]) / self.dy, 0.0, ny - 1.0)
        i = np.minimum(fx.astype(int), nx - 2)
        j = np.minimum(fy.astype(int), ny - 2)
        tx, ty = fx - i, fy - j
        return bilinear(field, i, j, tx, ty)
