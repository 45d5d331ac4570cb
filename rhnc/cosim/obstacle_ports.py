"""Which recorded obstacles are true and which are a tracker's estimates, read from the participants.

The controller and the trigger take whatever feeds their ``obstacles`` input: the traffic
participant's true targets, or a tracker's estimates of them.  The ``encounter`` and
``colregs`` analyses always judge the true tracks (what the ship really passed), and the
``tracking`` analysis compares the estimates with them.  A participant whose class sets
``estimates_targets = True`` publishes estimates; the truth is then the ``obstacles``
output of the first participant that does not.
"""

from __future__ import annotations


def _source(scenario, port: str) -> tuple[str, str] | None:
    for connection in scenario.connections:
        if connection.target_port == port:
            return connection.source, connection.source_port
    return None


def true_obstacles_column(scenario, cosim) -> str | None:
    """Column of the true obstacles (the array's prefix), or None when no obstacles are connected."""
    fed = _source(scenario, "obstacles")
    if fed is None:
        return None
    if not getattr(cosim.participant(fed[0]), "estimates_targets", False):
        return f"{fed[0]}.{fed[1]}"
    for participant in cosim.participants:
        if "obstacles" in participant.output_names and not getattr(participant, "estimates_targets", False):
            return f"{participant.name}.obstacles"
    return None


def estimated_obstacles_participant(scenario, cosim) -> str | None:
    """Name of the participant whose estimates feed an ``obstacles`` input, or None."""
    fed = _source(scenario, "obstacles")
    if fed is not None and getattr(cosim.participant(fed[0]), "estimates_targets", False):
        return fed[0]
    return None
