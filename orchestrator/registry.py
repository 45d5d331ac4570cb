"""Python participant types a scenario can name with ``type = "..."``.

Each entry maps a type name to ``"module:Class"``; the class provides
``from_options(name, options, context) -> Participant`` (see
:mod:`orchestrator.participant`).  Users plug in their own participants with
``type = "python"`` and ``class = "package.module:Class"`` instead.
"""

PARTICIPANT_TYPES = {
    "scripted_tau": "orchestrator.scripted:ScriptedTau",
    "scripted_rudder": "orchestrator.scripted:ScriptedRudder",
    "navigation": "rhnc.navigation_participant:NavigationParticipant",
    "control": "rhnc.control_participant:ControlParticipant",
    "traffic": "rhnc.traffic:TrafficParticipant",
    "reference_path": "rhnc.reference_participant:ReferencePathParticipant",
    "goal": "rhnc.goal:GoalMonitor",
    "allocation": "rhnc.allocation:AllocationParticipant",
}

#: Comparison extensions: a table of that name in a comparison file hands the runs to
#: ``"module:Class"`` (``from_table``, ``run_overrides``, ``evaluate``, ``summarise_sweep``;
#: see :mod:`orchestrator.compare`), which adds its own runs, tables and figures.
COMPARISON_EXTENSIONS = {
    "voyage": "rhnc.voyage_comparison:VoyageComparison",
}
