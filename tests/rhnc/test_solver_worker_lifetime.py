"""The NMPC's solver worker ends with the controller's process, also in the middle of a solve."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import psutil

CONTROLLER = textwrap.dedent("""
    import os, signal, sys, threading, time
    import numpy as np
    from rhnc.control.solver_watchdog import BoundedSolver

    class Busy:  # a solve that loops for a minute, as one in native code on a state out of range
        def __call__(self, **arguments):
            end = time.monotonic() + 60.0
            while time.monotonic() < end:
                pass
        def stats(self):
            return {}

    bounded = BoundedSolver({"nlp": Busy()}, {"nlp": Busy}, wall_time_s=120.0)
    bounded.start()
    print(bounded._pid, flush=True)
    threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGKILL)).start()  # killed mid-solve
    bounded.solve("nlp", x0=np.zeros(2))
""")


def alive(pid: int) -> bool:
    try:
        return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
    except psutil.Error:  # gone (or a zombie psutil will not read)
        return False


def test_a_worker_busy_in_a_solve_ends_when_the_controller_is_killed():
    process = subprocess.Popen([sys.executable, "-c", CONTROLLER], stdout=subprocess.PIPE, text=True)
    worker = int(process.stdout.readline())  # not read to its end: a surviving worker holds it open
    assert process.wait(timeout=60) == -signal.SIGKILL
    process.stdout.close()
    deadline = time.monotonic() + 10.0
    while alive(worker) and time.monotonic() < deadline:
        time.sleep(0.1)
    survived = alive(worker)
    if survived:
        os.kill(worker, signal.SIGKILL)
    assert not survived, "the solver worker outlived the controller's process"
