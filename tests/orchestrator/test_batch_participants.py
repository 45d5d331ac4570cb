"""A helm for batch tests: constant surge force, and ways to fail (no tests in this module)."""

import os

from orchestrator.errors import ScenarioError
from orchestrator.participant import Participant, reject_unknown_options


class TestHelm(Participant):
    """Constant tau; ``die_at_s`` ends the worker process abruptly, ``refuse`` fails the build."""

    __test__ = False  # not a pytest test class

    def __init__(self, name, tau_u, die_at_s, interrupt_batch_at_s=None):
        super().__init__(name)
        self.tau_u, self.die_at_s = tau_u, die_at_s
        self.interrupt_batch_at_s = interrupt_batch_at_s

    @classmethod
    def from_options(cls, name, options, context):
        reject_unknown_options(options, ("tau_u_N", "die_at_s", "refuse", "interrupt_batch_at_s"),
                               context.where + ".options")
        if options.get("refuse"):
            raise ScenarioError(f"{context.where}.options.refuse: this helm refuses to be built")
        return cls(name, float(options.get("tau_u_N", 7.7e5)), options.get("die_at_s"),
                   options.get("interrupt_batch_at_s"))

    @property
    def input_names(self):
        return []

    @property
    def output_names(self):
        return ["tau_u", "tau_r"]

    def setup(self, start_time, inputs):
        return {"tau_u": self.tau_u, "tau_r": 0.0}

    def step(self, time, step_size, inputs):
        if self.die_at_s is not None and time >= self.die_at_s:
            os._exit(17)  # a crash the Python code cannot catch, like a segfault in an FMU
        if self.interrupt_batch_at_s is not None and time == self.interrupt_batch_at_s:
            import signal

            os.kill(os.getppid(), signal.SIGINT)  # Ctrl-C to the batch process alone
        return {"tau_u": self.tau_u, "tau_r": 3.3e8 if time >= 30.0 else 0.0}
