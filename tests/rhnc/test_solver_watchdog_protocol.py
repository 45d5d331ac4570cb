"""The solver watchdog's worker protocol, run in this process (the worker's loop fed by a
scripted pipe end), and what a bounded solve returns when its worker stops or dies."""

import math
import os
import signal
import threading
import time

import numpy as np
import psutil
import pytest

from rhnc.control.solver_watchdog import WALL_TIME_STATUS, BoundedSolver, SolveOutcome, SolverError, _outcome, _serve


class ScriptedEnd:
    """The worker's end of the pipe: hands out the scripted requests, then the end of the pipe
    (EOFError, as when the controller closes its end); keeps what the worker sends. ``broken``:
    sending fails (BrokenPipeError) from that answer on, as when the controller has gone."""

    def __init__(self, requests, broken=None):
        self.requests = list(requests)
        self.sent = []
        self.received = 0
        self.broken = broken

    def recv(self):
        if not self.requests:
            raise EOFError
        self.received += 1
        return self.requests.pop(0)

    def send(self, message):
        if self.broken is not None and len(self.sent) >= self.broken:
            raise BrokenPipeError
        self.sent.append(message)


class Counting:
    """A solver that returns x0 + its call count, and reports its calls as iterations (a new
    object starts at 1 again)."""

    built = 0

    def __init__(self, burn_cpu_s=0.0):
        Counting.built += 1
        self.calls = 0
        busy(burn_cpu_s)  # the cost of building a solver

    def __call__(self, **arguments):
        self.calls += 1
        return {"x": np.asarray(arguments["x0"]) + self.calls, "g": np.zeros(1), "f": float(self.calls)}

    def stats(self):
        return {"success": True, "iter_count": self.calls, "return_status": "Solve_Succeeded"}


def busy(cpu_s):
    """Spend ``cpu_s`` of this process's processor time."""
    end = time.process_time() + cpu_s
    x = 0.0
    while time.process_time() < end:
        x = math.sin(x + 1.0)


@pytest.fixture
def sigint_restored():
    """The worker's loop ignores Ctrl-C in its process: here that is the test's, so it is put back."""
    before = signal.getsignal(signal.SIGINT)
    yield
    signal.signal(signal.SIGINT, before)


def serve(requests, solvers, factories=None, renew=None, broken=None, cpu_time_s=None):
    """The worker's loop on ``requests``: (name, arguments) asks for no iteration cap and no limit
    of its own, (name, arguments, cap, limit) for them."""
    end = ScriptedEnd([request if len(request) == 4 else (*request, None, None) for request in requests], broken)
    _serve(end, solvers, factories or {}, renew, cpu_time_s)
    return end


def test_the_worker_answers_each_request_in_order_until_the_pipe_ends(sigint_restored):
    end = serve([("nlp", {"x0": np.zeros(2)}), ("nlp", {"x0": np.ones(2)}), ("nlp", {"x0": np.zeros(2)})],
                {"nlp": Counting()})
    assert [type(message) for message in end.sent] == [SolveOutcome] * 3
    np.testing.assert_array_equal([message.x for message in end.sent], [[1, 1], [3, 3], [3, 3]])
    assert [message.iterations for message in end.sent] == [1, 2, 3]  # one object serves every call


def test_the_worker_ignores_ctrl_c_which_is_the_controllers_to_handle(sigint_restored):
    signal.signal(signal.SIGINT, signal.default_int_handler)
    serve([], {})
    assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN


def test_the_worker_builds_a_solver_it_lacks_once_and_keeps_those_it_has(sigint_restored):
    Counting.built = 0
    given = Counting()
    end = serve([("nlp", {"x0": np.zeros(1)}), ("other", {"x0": np.zeros(1)}), ("other", {"x0": np.zeros(1)}),
                 ("nlp", {"x0": np.zeros(1)})], {"nlp": given}, {"nlp": Counting, "other": Counting})
    assert Counting.built == 2  # the given one and "other", built at its first request
    assert [message.iterations for message in end.sent] == [1, 1, 2, 2]
    assert given.calls == 2


def test_a_solver_that_raises_is_answered_with_its_error_and_the_worker_goes_on(sigint_restored):
    class Refusing:
        def __call__(self, **arguments):
            raise RuntimeError("Fatrop option   not\n supported: tol_acceptable")

    end = serve([("bad", {"x0": np.zeros(1)}), ("missing", {"x0": np.zeros(1)}), ("nlp", {"x0": np.zeros(1)})],
                {"bad": Refusing(), "nlp": Counting()})
    assert isinstance(end.sent[0], SolverError)
    assert str(end.sent[0]) == "RuntimeError: Fatrop option not supported: tol_acceptable"
    assert isinstance(end.sent[1], SolverError) and "KeyError" in str(end.sent[1])  # no factory for it
    assert isinstance(end.sent[2], SolveOutcome) and end.sent[2].success


def test_the_worker_stops_when_its_answer_cannot_be_sent(sigint_restored):
    class RefusingOnce:
        def __call__(self, **arguments):
            raise RuntimeError("no")

    for solver in (Counting(), RefusingOnce()):  # an outcome or an error: the controller has gone
        end = serve([("nlp", {"x0": np.zeros(1)}), ("nlp", {"x0": np.zeros(1)})], {"nlp": solver}, broken=0)
        assert end.received == 1 and end.sent == []


def test_the_worker_reports_its_processor_time_per_call_and_a_renewal_with_the_next_answer(sigint_restored):
    class Burning(Counting):
        def __call__(self, **arguments):
            busy(0.05)
            return super().__call__(**arguments)

    built = []

    def factory():
        built.append(1)
        return Counting(burn_cpu_s=0.1)

    # renewed after the first answer only: the second answer carries the renewal's time, the third none
    end = serve([("nlp", {"x0": np.zeros(1)})] * 3, {"nlp": Burning()}, {"nlp": factory},
                renew=lambda outcome: outcome.f == 1.0 and len(built) == 0)
    first, second, third = end.sent
    assert first.cpu_time_s >= 0.05  # the worker's share of the call, the solve included
    assert first.preparation_cpu_s == 0.0
    assert second.preparation_cpu_s >= 0.1
    assert third.preparation_cpu_s == 0.0
    assert len(built) == 1


def test_a_worker_never_renewing_reports_no_preparation_time(sigint_restored):
    end = serve([("nlp", {"x0": np.zeros(1)})] * 3, {"nlp": Counting()}, {"nlp": Counting},
                renew=lambda outcome: False)
    assert [message.preparation_cpu_s for message in end.sent] == [0.0, 0.0, 0.0]


def test_an_ipopt_stop_at_its_acceptable_level_is_reported_apart():
    class Ipopt:
        def __init__(self, status):
            self.status = status

        def stats(self):
            return {"success": False, "iter_count": 9, "return_status": self.status}

    result = {"x": np.zeros(2), "g": np.zeros(1), "f": 0.0}
    assert _outcome(Ipopt("Solved_To_Acceptable_Level"), result, 0.0, 0.0).acceptable
    assert not _outcome(Ipopt("Maximum_Iterations_Exceeded"), result, 0.0, 0.0).acceptable


class Dying:
    """A solver whose process dies in the call (out of memory, a crash in native code)."""

    def __call__(self, **arguments):
        os._exit(3)


def assert_stopped_shape(outcome, n, ng):
    assert outcome.x.shape == (n,) and np.isnan(outcome.x).all()
    assert outcome.g.shape == (ng,) and np.isnan(outcome.g).all()
    assert outcome.lam_x.shape == (n,) and np.isnan(outcome.lam_x).all()
    assert outcome.lam_g.shape == (ng,) and np.isnan(outcome.lam_g).all()
    assert isinstance(outcome.f, float) and math.isnan(outcome.f)
    assert not outcome.success and outcome.iterations == -1


def test_a_solve_whose_worker_dies_returns_no_point_and_a_new_worker_serves_the_next():
    bounded = BoundedSolver({"dying": Dying(), "nlp": Counting()}, {}, wall_time_s=30.0)
    try:
        died = bounded.solve("dying", x0=np.zeros(4), lbg=np.zeros(3))
        assert died.status == "solver_worker_died" and not died.timed_out and died.stopped_by == ""
        assert_stopped_shape(died, 4, 3)
        assert 0.0 < died.wall_time_s < 30.0
        assert bounded.timeouts == 0
        after = bounded.solve("nlp", x0=np.zeros(4))
        assert after.success and after.iterations == 1
    finally:
        bounded.close()


def test_a_stopped_solve_has_the_shapes_of_its_arguments_and_says_whether_a_limit_stopped_it():
    stopped = BoundedSolver._stopped({"x0": np.zeros(5), "lbg": np.zeros(2)}, 1.5, WALL_TIME_STATUS)
    assert_stopped_shape(stopped, 5, 2)
    assert stopped.timed_out and stopped.wall_time_s == 1.5 and stopped.status == WALL_TIME_STATUS
    assert not BoundedSolver._stopped({"x0": np.zeros(5)}, 1.5, "solver_worker_died").timed_out


def test_without_fork_solves_run_in_this_process_under_no_time_limit(monkeypatch):
    monkeypatch.delattr(os, "fork")
    solver = Counting()
    bounded = BoundedSolver({"nlp": solver}, {}, wall_time_s=1.0, cpu_time_s=1.0)
    assert not bounded.in_worker and bounded.wall_time_s is None and bounded.cpu_time_s is None
    assert bounded.solve("nlp", x0=np.zeros(1)).success
    assert solver.calls == 1  # this process's object served the call


def test_the_processor_time_limit_counts_the_workers_time_not_the_controllers():
    class Sleeping(Counting):  # the worker waits, using (almost) no processor time, until the controller's
        def __call__(self, **arguments):  # process has used more than the limit (however loaded the machine)
            controller = psutil.Process(os.getppid())
            start = sum(controller.cpu_times()[:2])
            deadline = time.monotonic() + 45.0
            while sum(controller.cpu_times()[:2]) - start < 0.6 and time.monotonic() < deadline:
                time.sleep(0.05)
            return super().__call__(**arguments)

    stop = threading.Event()

    def spin():  # the controller's process is busy meanwhile (another thread of it)
        x = 0.0
        while not stop.is_set():
            x = math.sin(x + 1.0)

    bounded = BoundedSolver({"nlp": Sleeping()}, {}, wall_time_s=60.0, cpu_time_s=0.3)
    spinner = threading.Thread(target=spin)
    try:
        bounded.start()
        spinner.start()
        outcome = bounded.solve("nlp", x0=np.zeros(1))
    finally:
        stop.set()
        spinner.join()
        bounded.close()
    assert outcome.success and not outcome.timed_out


def test_a_worker_whose_controller_closes_the_pipe_exits_cleanly():
    bounded = BoundedSolver({"nlp": Counting()}, {}, wall_time_s=30.0)
    bounded.start()
    pid = bounded._pid
    bounded._connection.close()  # the controller's end closed: the worker's loop ends
    deadline = time.monotonic() + 20.0
    status = None
    while time.monotonic() < deadline:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            break
        time.sleep(0.05)
    else:
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
    bounded._finalizer.detach()
    bounded._pid = bounded._connection = bounded._finalizer = None
    assert status is not None and os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0

