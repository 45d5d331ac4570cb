"""Land and no-go areas as NMPC constraints: the nearest edges of a chart near the predicted track.

The NMPC keeps its obstacles outside circles (:mod:`rhnc.control.nmpc_problem`); a coastline
enters the same way, through slots of its own after the targets' slots.  Every control step
the chart (:class:`rhnc.chart.chart.BoundaryIndex`) gives, for each point of the predicted
track (the previous plan shifted, and the reference), the nearest point ``q`` of any area's
edge.  The track's points outside the areas are cut
into as many consecutive pieces of the horizon as there are coastline slots, and each
piece's nearest edge point becomes one constraint: a stationary circle of radius ``R + c``
around ``q - n R``, where ``n`` is the unit normal at ``q`` from the area towards the track
point and ``c`` the chart's declared clearance.  Outside the circle is at least ``c`` from
the small circle of radius ``R`` touching the edge at ``q`` from the land side, which lies
in the area wherever the area is at least ``2 R`` deep (its bulge past a right-angled
corner is ``0.29 R``): the constraint never asks more than the clearance does.  Along a
straight edge it asks ``c`` at ``q`` and less beside it, ``sqrt((R + c)² - s²) - R`` at a
distance ``s`` along the edge: with ``R = c / 4`` (``TANGENT_SHARE``) 2.5 % less at
``s = c / 4``, 10 % at ``s = c / 2``; the pieces' points lie one or two intervals' sailing
apart.  Track points inside an area give none: their nearest edge does not say which way
out (a reference across a headland would be pushed to the headland's far side).

The constraint is on whenever a chart is given, whatever the event trigger (land does not
move in and out of a detection range).  Like the targets' circles it is softened by the
stage slack when no plan keeps it (``collision_slack_weight``), and a ship already inside
the clearance (pushed there, or started there) is asked only to come no closer than it
is, as the route search asks of a leg from inside (:meth:`rhnc.chart.chart.Chart.legs_clear`):
the way out.  An edge point farther from every track point than the clearance plus half
the horizon's length gets no slot.
"""

from __future__ import annotations

import numpy as np

from rhnc.control.nmpc_problem import OBSTACLE_FIELDS

#: Radius of the circle touching the edge from the land side, as a share of the clearance.
TANGENT_SHARE = 0.25
#: Share of its present distance to a constraint's circle a ship inside the clearance keeps.
WAY_OUT_SHARE = 0.999


class CoastlineDomains:
    """The coastline slots of the NMPC's obstacle parameters.

    Parameters
    ----------
    chart : rhnc.chart.chart.Chart
        Areas and declared clearance.
    slots : int
        Coastline slots (constraints per substep).
    """

    def __init__(self, chart, slots: int) -> None:
        from rhnc.chart.chart import BoundaryIndex

        if slots < 1:
            raise ValueError(f"coastline slots must be >= 1, got {slots}")
        self.index = BoundaryIndex(chart)
        self.clearance_m = float(chart.clearance_m)
        self.slots = slots
        self.nearest_m = np.inf  # least distance of the last step's track to an area [m]

    def parameters(self, track_m: np.ndarray, position_m: np.ndarray, origin_m: np.ndarray, length_scale_m: float,
                   closing_speed_mps: float, substep_s: float, horizon_length_m: float) -> np.ndarray:
        """Slot parameters (OBSTACLE_FIELDS x slots, scaled like the targets').

        Parameters
        ----------
        track_m : (k, n, 2) array
            Predicted tracks (north, east [m]) at the horizon's n instants, k of them (the
            previous plan, the reference); a piece of the horizon takes the nearest edge
            point of any of them.
        position_m : (2,) array
            The ship now [m].
        origin_m : (2,) array
            What the scaled problem measures positions from [m].
        length_scale_m : float
            L [m].
        closing_speed_mps : float
            Own speed bound for the chord inflation [m/s].
        substep_s : float
            Time between constraint checks [s].
        horizon_length_m : float
            Distance sailed over the horizon [m].
        """
        L = length_scale_m
        slots = np.zeros((OBSTACLE_FIELDS, self.slots))
        slots[6, :] = 1.0  # harmless radius for inactive slots
        tracks = np.asarray(track_m, dtype=float).reshape(-1, np.shape(track_m)[-2], 2)
        k, n = tracks.shape[:2]
        nearest, distance, inside = self.index.nearest(tracks.reshape(-1, 2))
        self.nearest_m = float(np.min(np.where(inside, 0.0, distance), initial=np.inf))
        radius = TANGENT_SHARE * self.clearance_m
        reach = self.clearance_m + 0.5 * horizon_length_m
        signed = np.where(inside, np.inf, distance).reshape(k, n)
        position = np.asarray(position_m, dtype=float)
        chosen: list[np.ndarray] = []
        for columns in np.array_split(np.arange(n), self.slots):
            if columns.size == 0:
                continue
            block = signed[:, columns]
            row, column = np.unravel_index(np.argmin(block), block.shape)
            flat = row * n + columns[column]
            if not signed[row, columns[column]] < reach:
                continue
            q = nearest[flat]
            point = tracks.reshape(-1, 2)[flat]
            normal = point - q
            length = float(np.hypot(*normal))
            if length < 1e-6:  # the track point on the edge itself: the normal from the ship
                normal, length = position - q, float(np.hypot(*(position - q)))
                if length < 1e-6:
                    continue
            normal = normal / length
            if any(np.hypot(*(q - other)) < 1.0 for other in chosen):
                continue  # the same edge point twice: one constraint
            chosen.append(q)
            centre = q - normal * radius
            domain = min(radius + self.clearance_m, WAY_OUT_SHARE * float(np.hypot(*(position - centre))))
            inflation = (closing_speed_mps * substep_s / (2.0 * domain)) ** 2
            slot = len(chosen) - 1
            slots[:, slot] = [(centre[0] - origin_m[0]) / L, (centre[1] - origin_m[1]) / L, 0.0, 0.0, 0.0, 0.0,
                              domain / L, 0.0, inflation, 1.0]
        return slots
