"""Small Python participants the orchestrator tests wire into scenarios."""

import math

import numpy as np

from orchestrator.participant import Participant, reject_unknown_options


class Clock(Participant):
    """Outputs its own step count and the time it was stepped at."""

    def __init__(self, name, nan_at=None):
        super().__init__(name)
        self.count = 0
        self.nan_at = nan_at
        self.calls = []

    @classmethod
    def from_options(cls, name, options, context):
        reject_unknown_options(options, ("nan_at_s",), context.where + ".options")
        return cls(name, options.get("nan_at_s"))

    input_names = property(lambda self: [])
    output_names = property(lambda self: ["count", "time", "vector"])

    def setup(self, start_time, inputs):
        return {"count": 0.0, "time": start_time, "vector": np.array([0.0, 1.0])}

    def step(self, time, step_size, inputs):
        self.count += 1
        self.calls.append((time, step_size))
        value = math.nan if self.nan_at is not None and time >= self.nan_at else float(self.count)
        return {"count": value, "time": time, "vector": np.array([time, 2 * time])}

    def summary(self):
        return {"steps": self.count}

    def tables(self):
        return {"calls": [{"time": t, "step": h} for t, h in self.calls]}


class Echo(Participant):
    """Copies its input `value` to its output `seen`, and remembers what it saw."""

    def __init__(self, name):
        super().__init__(name)
        self.seen = []

    @classmethod
    def from_options(cls, name, options, context):
        reject_unknown_options(options, (), context.where + ".options")
        return cls(name)

    input_names = property(lambda self: ["value"])
    output_names = property(lambda self: ["seen"])

    def setup(self, start_time, inputs):
        return {"seen": float(inputs.get("value", -1.0))}

    def step(self, time, step_size, inputs):
        self.seen.append((time, float(inputs["value"])))
        return {"seen": float(inputs["value"])}


class OneOutput(Participant):
    """Base of the participants below that misbehave from ``at_s`` on: one output ``ok``
    (1 at set-up and at every step that returns); each option of ``DEFAULTS`` (name: default)
    becomes an attribute of the same name."""

    DEFAULTS: dict = {}

    @classmethod
    def from_options(cls, name, options, context):
        participant = cls(name)
        participant.at = options.get("at_s", 0.0)
        for key, default in cls.DEFAULTS.items():
            setattr(participant, key, options.get(key, default))
        return participant

    input_names = property(lambda self: [])
    output_names = property(lambda self: ["ok"])

    def setup(self, start_time, inputs):
        return {"ok": 1.0}

    def block(self, time, label, wait):
        """From ``at_s`` on, calls ``wait`` for ever and swallows KeyboardInterrupt (a hung
        library call); says ``<label>: blocking`` on stdout once, when it begins."""
        said = False
        while time >= self.at:
            try:
                if not said:
                    said = True
                    print(f"{label}: blocking", flush=True)
                wait()
            except KeyboardInterrupt:
                pass
        return {"ok": 1.0}


class Crash(OneOutput):
    """Raises a plain exception at a given time, or in its set-up (a participant's own bug)."""

    DEFAULTS = {"in_setup": False}

    def setup(self, start_time, inputs):
        if self.in_setup:
            raise np.linalg.LinAlgError("Failed to find a finite solution.")
        return {"ok": 1.0}

    def step(self, time, step_size, inputs):
        if time >= self.at:
            raise RuntimeError("boom")
        return {"ok": 1.0}


class Stubborn(OneOutput):
    """From ``at_s`` on, a step that never returns and swallows KeyboardInterrupt (a hung library call)."""

    def step(self, time, step_size, inputs):
        import time as wallclock

        return self.block(time, "stubborn", lambda: wallclock.sleep(3600.0))


class Beacon(Participant):
    """Prints ``beacon: t = <time> s`` on stdout at every step from ``from_s`` on (for tests that watch a run)."""

    @classmethod
    def from_options(cls, name, options, context):
        participant = cls(name)
        participant.start = options.get("from_s", 0.0)
        return participant

    input_names = property(lambda self: [])
    output_names = property(lambda self: ["alive"])

    def setup(self, start_time, inputs):
        return {"alive": 1.0}

    def step(self, time, step_size, inputs):
        if time >= self.start:
            print(f"beacon: t = {time:g} s", flush=True)
        return {"alive": 1.0}


class Swallower(OneOutput):
    """At ``at_s`` signals its own process (SIGINT) and swallows the KeyboardInterrupt, as a
    library that turns Ctrl-C into a failed call of its own does; then returns normally."""

    def step(self, time, step_size, inputs):
        import os
        import signal
        import time as wallclock

        if time == self.at:
            try:
                os.kill(os.getpid(), signal.SIGINT)
                wallclock.sleep(5.0)  # the handler runs here and raises
            except KeyboardInterrupt:
                pass  # swallowed: the caller never sees it
        return {"ok": 1.0}


class Hog(OneOutput):
    """From ``at_s`` on, a native call that holds the interpreter lock and is restarted after
    every signal (like a library build that never checks for signals)."""

    def step(self, time, step_size, inputs):
        import ctypes

        libc = ctypes.PyDLL(None)  # PyDLL: the call keeps the interpreter lock
        return self.block(time, "hog", lambda: libc.sleep(1000))


class Sleeper(OneOutput):
    """From ``at_s`` on, a step that sleeps ``sleep_s``; with ``swallow`` it catches everything
    and sleeps again (a participant that no Python exception can stop); ``setup_sleep_s``: a
    set-up that sleeps that long."""

    DEFAULTS = {"sleep_s": 3600.0, "swallow": False, "unless_exists": None, "busy": False, "setup_sleep_s": 0.0}

    def setup(self, start_time, inputs):
        import time as wallclock

        wallclock.sleep(self.setup_sleep_s)
        return {"ok": 1.0}

    def step(self, time, step_size, inputs):
        import time as wallclock

        import os

        if time >= self.at and not (self.unless_exists and os.path.exists(self.unless_exists)):
            print(f"sleeper: sleeping at t = {time:g} s", flush=True)
            while True:
                try:
                    if self.busy:  # a Python loop that computes rather than sleeps
                        end = wallclock.monotonic() + self.sleep_s
                        while wallclock.monotonic() < end:
                            pass
                    else:
                        wallclock.sleep(self.sleep_s)
                    break
                except BaseException:  # noqa: B036 - the point: it swallows even the time limit
                    if not self.swallow:
                        raise
        return {"ok": 1.0}


def ctrl_c() -> None:
    """Send SIGINT to this process, as Ctrl-C in its terminal does, and wait for it to arrive."""
    import os
    import signal
    import time

    os.kill(os.getpid(), signal.SIGINT)
    for _ in range(500):  # the handler raises KeyboardInterrupt at the next bytecode
        time.sleep(0.01)


class Misbehaving(OneOutput):
    """Fails in one of the ways a participant can fail outside a plain exception in its step.

    ``how``: ``"exit"`` (sys.exit(5) in its step at ``at_s``), ``"terminate"`` (terminate()
    raises), ``"summary"`` (summary() raises), ``"unserialisable"`` (a summary JSON cannot
    hold), ``"options"`` (from_options raises ValueError), ``"nan_setup"`` (a NaN output at
    set-up, past the checks a scenario file gets), ``"interrupt_terminate"`` and
    ``"interrupt_summary"`` (Ctrl-C arrives while terminate() or summary() runs).
    """

    @classmethod
    def from_options(cls, name, options, context):
        how = options.get("how")
        if how == "options":
            raise ValueError("gain must be positive")
        if how == "exit_options":
            import sys

            sys.exit(4)
        participant = super().from_options(name, options, context)
        participant.how = how
        participant.steps = 0
        return participant

    def setup(self, start_time, inputs):
        return {"ok": float("nan") if self.how == "nan_setup" else 1.0}

    def step(self, time, step_size, inputs):
        import sys

        self.steps += 1
        if self.how == "exit" and time >= self.at:
            sys.exit(5)
        return {"ok": 1.0}

    def terminate(self):
        if self.how == "terminate":
            raise OSError("device busy")
        if self.how == "interrupt_terminate":
            ctrl_c()

    def summary(self):
        if self.how == "interrupt_summary":
            ctrl_c()
        if self.how == "summary":
            raise ZeroDivisionError("division by zero")
        if self.how == "unserialisable":
            return {"steps": self.steps, "model": object()}
        return {"steps": self.steps}


class SelfKiller(OneOutput):
    """At ``at_s`` sends SIGKILL to its own process unless the file ``unless_exists`` exists
    (what the out-of-memory killer or an operator does to a worker); with ``exit``, calls
    ``os._exit(7)`` instead."""

    DEFAULTS = {"unless_exists": None, "crash": False, "exit": False}

    def step(self, time, step_size, inputs):
        import os
        import signal

        if time >= self.at and self.crash:
            raise RuntimeError("a bug of its own")
        if time >= self.at and not (self.unless_exists and os.path.exists(self.unless_exists)):
            if self.exit:  # a library ending the process without unwinding
                os._exit(7)
            os.kill(os.getpid(), signal.SIGKILL)
        return {"ok": 1.0}


class Probe(Participant):
    """Records what the master tells it (build context, sources, calls, the reported position)
    and outputs its step's start time as ``value``; options make it misbehave on purpose."""

    def __init__(self, name, options, context):
        super().__init__(name)
        self.options = options
        self.context = context
        self.sources = None
        self.calls = []
        self.positions = []
        self.outputs_at_step_end = bool(options.get("at_step_end", False))
        self.checks_outputs_finite = bool(options.get("checks_finite", False))

    @classmethod
    def from_options(cls, name, options, context):
        return cls(name, dict(options), context)

    input_names = property(lambda self: list(self.options.get("inputs", ["value"])))

    def remove_files(self):
        """What a watchdog calls on a run that is ending: only counted here."""
        self.removed = getattr(self, "removed", 0) + 1
    output_names = property(lambda self: ["value", "extra"] if self.options.get("declare_extra") else ["value"])

    def connected(self, sources):
        self.sources = dict(sources)

    def _where(self):
        from orchestrator import interrupts

        self.positions.append(interrupts._state.where())

    def setup(self, start_time, inputs):
        self._where()
        self.setup_inputs = dict(inputs)
        return {"value": float(start_time)}

    def step(self, time, step_size, inputs):
        from orchestrator import interrupts
        from orchestrator.errors import ModelError

        self._where()
        self.calls.append((time, step_size))
        at = self.options.get("at_s", math.inf)
        if time >= at:
            what = self.options.get("misbehave")
            if what == "model_error":
                raise ModelError("refused the step")
            if what == "interrupt_as_error":  # a library that turns a signal into its own error
                interrupts._state.signal_name = "SIGTERM"
                raise RuntimeError("solver interrupted")
            if what == "undeclared":
                return {"value": time, "surprise": 1.0}
            if what == "nan":
                return {"value": math.nan}
            if what == "integer":
                return {"value": int(time)}
            if what == "numpy_scalar":
                return {"value": np.float64(time)}
            if what == "numpy_nan":
                return {"value": np.float64("nan")}
        return {"value": float(time)}

    def summary(self):
        if self.options.get("bad_summary"):
            raise ValueError("no summary today")
        return {"calls": len(self.calls)}


class NotAParticipant:
    """Has from_options, but builds something else."""

    @classmethod
    def from_options(cls, name, options, context):
        return object()


class Compiling(Participant):
    """Says at INFO, as the NMPC does on a fresh machine, that it compiles while it is built;
    and at INFO again in each step (a line the console must not show)."""

    @classmethod
    def from_options(cls, name, options, context):
        import logging

        logging.getLogger("orchestrator.sample_build").info("compiling its model into /cache/model.so (once per "
                                                            "machine)")
        return cls(name)

    input_names = property(lambda self: [])
    output_names = property(lambda self: ["ok"])

    def setup(self, start_time, inputs):
        return {"ok": 1.0}

    def step(self, time, step_size, inputs):
        import logging

        logging.getLogger("orchestrator.sample_build").info("stepping at %g s", time)
        return {"ok": 1.0}


class Late(Participant):
    """Declares outputs ``a`` and ``b`` but gives ``b`` only from its first step on."""

    @classmethod
    def from_options(cls, name, options, context):
        return cls(name)

    input_names = property(lambda self: [])
    output_names = property(lambda self: ["a", "b"])

    def setup(self, start_time, inputs):
        return {"a": 0.5}

    def step(self, time, step_size, inputs):
        return {"a": time + 1.0, "b": -(time + 1.0)}


class Collector(Participant):
    """Records the inputs ``a`` and ``b`` it is given at every step."""

    def __init__(self, name):
        super().__init__(name)
        self.seen = []

    @classmethod
    def from_options(cls, name, options, context):
        return cls(name)

    input_names = property(lambda self: ["a", "b"])
    output_names = property(lambda self: ["ok"])

    def setup(self, start_time, inputs):
        return {"ok": 1.0}

    def step(self, time, step_size, inputs):
        self.seen.append(dict(inputs))
        return {"ok": 1.0}


class Drifter(Participant):
    """One float output that turns NaN from t = 2 s; says nothing about checking its outputs."""

    @classmethod
    def from_options(cls, name, options, context):
        return cls(name)

    input_names = property(lambda self: [])
    output_names = property(lambda self: ["value"])

    def setup(self, start_time, inputs):
        return {"value": 0.0}

    def step(self, time, step_size, inputs):
        return {"value": math.nan if time >= 2.0 else time}
