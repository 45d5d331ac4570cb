"""batches/weather_set.toml: Experiment 2's RHNC scenario over the 30 members of the storm set."""

from pathlib import Path


from orchestrator.batch_spec import load_batch
from orchestrator.scenario import load_scenario
from rhnc.weather.metocean_sources import from_scenario_table
from rhnc.weather.weather_generators import STORM_SET_SIZE, storm_set_member

BATCH = Path(__file__).parents[2] / "batches" / "weather_set.toml"


def test_batch_runs_every_member_of_the_set_each_in_its_own_storm():
    batch = load_batch(BATCH)
    runs = batch.runs()
    assert sorted(run.overrides["metocean.member"] for run in runs) == list(range(STORM_SET_SIZE))
    assert len({run.run_id for run in runs}) == STORM_SET_SIZE
    peaks = []
    for run in runs[:3]:
        scenario = load_scenario(batch.scenario, run.overrides)
        field = from_scenario_table(scenario.metocean, scenario.directory, "weather_set")
        member = run.overrides["metocean.member"]
        assert f"storm_set seed 2026 member {member} " in field.source
        peaks.append(storm_set_member(2026, member)["peak_wind_ms"])
        # the drawn peak is reached at the drawn centre (to the grid's 1 nm)
        centre = storm_set_member(2026, member)["centre_nm"]
        if 0 <= centre[0] <= 100 and 0 <= centre[1] <= 100:
            at_centre = field.sample(centre[0] * 1852.0, centre[1] * 1852.0)["wind_speed"]
            assert at_centre > 0.97 * peaks[-1]
    assert len(set(peaks)) == 3
