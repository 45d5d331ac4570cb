import textwrap

import pytest


@pytest.fixture
def write_scenario(tmp_path):
    """Write a scenario TOML (dedented) into tmp_path and return its path."""

    def write(text, name="scenario.toml"):
        path = tmp_path / name
        path.write_text(textwrap.dedent(text))
        return path

    return write


@pytest.fixture
def run_to_end(write_scenario):
    """Write a scenario, build its master, run it (no progress bar) and close it: the outcome."""

    def run(text):
        from orchestrator.master import CoSimulation
        from orchestrator.scenario import load_scenario

        cosim = CoSimulation(load_scenario(write_scenario(text)))
        try:
            return cosim.run(progress=False)
        finally:
            cosim.close()

    return run


@pytest.fixture
def write_small_batch(tmp_path):
    """Write test_batch's small batch (or ``text`` as the batch file) and its scenario into tmp_path:
    the batch file's path."""
    from test_batch import BATCH, SCENARIO

    def write(text=BATCH):
        (tmp_path / "short_turn.toml").write_text(SCENARIO)
        path = tmp_path / "small.toml"
        path.write_text(textwrap.dedent(text))
        return path

    return write


@pytest.fixture
def small_batch(write_small_batch):
    """test_batch's small batch and its scenario written into tmp_path: the batch file's path."""
    return write_small_batch()
