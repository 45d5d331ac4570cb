"""The settings of the NMPC's collision domains and COLREG decisions (:class:`DomainSettings`)."""

from __future__ import annotations

import dataclasses

from rhnc.encounters.colregs import STAND_ON_ACTION_RANGE_FACTOR, STAND_ON_ACTION_TCPA_S


@dataclasses.dataclass(frozen=True)
class DomainSettings:
    """How obstacles become collision domains.

    Attributes
    ----------
    own_radius_m : float
        R [m].
    colregs : bool
        Shape the domains by encounter class (else the paper's circles).
    clearance_margin_m : float
        Added to R + R_i [m].
    clearance_margin_growth_mps : float
        Growth of the margin per second of prediction [m/s].
    stand_on_action_tcpa_s, stand_on_action_range_factor : float
        Rule 17: when a stand-on ship acts, see :func:`rhnc.encounters.colregs.stand_on_must_act`
        (judged against R + R_i, without the margin, as the ``colregs`` analysis does).
    risk_cpa_m, risk_tcpa_s : float
        Risk of collision for the classification (see :func:`rhnc.encounters.colregs.classify`).
    alteration_deg : float
        Rule 8(b), 16: once the own ship gives way (or acts as stand-on ship), its heading
        is held at least this far off the reference heading it had when it began, and off
        the heading at the target's onset of risk, to the side the rules ask for, until the
        target is past and clear (0: no minimum alteration).  35 deg: a readily apparent alteration is commonly read as 30 deg or
        more of course over ground, and the bound holds the heading; in a cross wind the
        course over ground differs from it by the drift angle (2-6 deg in the paper's
        weather at 18 kn), and the course the change is seen from is the one at the onset.
        A bound of exactly 30 deg lands on either side of 30 deg.
    give_way_action_tcpa_s : float
        A give-way ship begins that alteration when the collision constraints are on and
        the target's CPA (predicted at the present velocities, inside ``risk_cpa_m``) is
        at most this far ahead [s].  15 min: an alteration is to be seen at least 5 min
        before the CPA; the turn itself takes 2-3 min, and turning away brings the CPA
        forward (with 12 min, overtaking ships altered 3.7 min before their CPA).
    """

    own_radius_m: float = 0.0
    colregs: bool = False
    clearance_margin_m: float = 0.0
    clearance_margin_growth_mps: float = 0.0
    stand_on_action_tcpa_s: float = STAND_ON_ACTION_TCPA_S
    stand_on_action_range_factor: float = STAND_ON_ACTION_RANGE_FACTOR
    risk_cpa_m: float = 2.0 * 1852.0
    risk_tcpa_s: float = 30.0 * 60.0
    alteration_deg: float = 35.0
    give_way_action_tcpa_s: float = 900.0
