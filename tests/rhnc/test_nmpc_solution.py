"""The NMPC's result of one step is built by name, never by position."""

import numpy as np
import pytest

from rhnc.control.nmpc_settings import NMPCSolution


def test_a_solution_is_built_by_keyword_only():
    fields = dict(tau=np.zeros(2), states=np.zeros((3, 6)), inputs=np.zeros((2, 2)), solve_time_s=0.1,
                  iterations=4, status="Solve_Succeeded", success=True, fallback=False, cost=1.0,
                  constraint_violation=0.0)
    solution = NMPCSolution(**fields)
    assert (solution.success, solution.fallback, solution.timed_out) == (True, False, False)
    with pytest.raises(TypeError):
        NMPCSolution(*fields.values())
