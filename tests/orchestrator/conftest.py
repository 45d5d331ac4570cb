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
