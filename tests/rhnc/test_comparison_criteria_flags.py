"""A comparison flags systems and baselines whose runs missed their own acceptance criteria."""

from types import SimpleNamespace

from rhnc.voyage.equal_arrival import ArrivalTrial, EqualArrival
from rhnc.voyage.voyage_comparison import unmet_criteria_flags


def test_runs_that_missed_their_criteria_are_flagged_and_others_not():
    near_land = SimpleNamespace(failed_criteria=["clearance kept: analyses.clearance.kept = False, not == True"])
    fine = SimpleNamespace(failed_criteria=[])
    baseline = EqualArrival(target_s=100.0, tolerance_s=1.0,
                            trials=[ArrivalTrial(10.0, 110.0, fine), ArrivalTrial(11.0, 100.0, near_land),
                                    ArrivalTrial(12.0, None, None)])
    flags = unmet_criteria_flags({"RHNC": fine, "other": near_land}, {"RHNC": baseline})
    assert flags == ["other: acceptance not met: clearance kept: analyses.clearance.kept = False, not == True",
                     "RHNC equal-arrival baseline: acceptance not met in some trials: clearance kept: "
                     "analyses.clearance.kept = False, not == True"]
    assert unmet_criteria_flags({"RHNC": fine}, {"RHNC": EqualArrival(100.0, 1.0, [ArrivalTrial(10.0, 100.0, fine)])}) == []
