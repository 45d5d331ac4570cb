"""Running a batch on a Dask distributed cluster, plain (``tcp://``) or encrypted and authenticated (``tls://``).

A Dask scheduler runs whatever its clients submit, so one that listens on a shared network
without TLS lets anyone who can reach it run code on its workers.  With ``tls://`` every
connection is encrypted and both ends show a certificate signed by the cluster's own
certificate authority: the batch gives its client certificate and key and the CA that
signed the scheduler's (``--tls-ca``, ``--tls-cert``, ``--tls-key``).  The recipe for a
cluster bound to a private address with TLS is in ``docs/batch.md``.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

#: Address schemes a batch accepts for ``--scheduler`` (``inproc://``: a cluster inside this process).
SCHEMES = ("tcp://", "tls://", "inproc://")


@dataclass(frozen=True)
class TlsFiles:
    """The PEM files of a TLS connection to the scheduler."""

    ca: Path
    cert: Path
    key: Path


def check_scheduler(address: str | None, ca=None, cert=None, key=None) -> TlsFiles | None:
    """The TLS files for ``address``, after checking that they fit it; raises ``BatchError`` (one line).

    ``tcp://host:port`` takes no TLS files; ``tls://host:port`` needs all three, and each must
    be a readable file.
    """
    from orchestrator.batch_run import BatchError

    given = {"--tls-ca": ca, "--tls-cert": cert, "--tls-key": key}
    if address is None:
        named = [option for option, value in given.items() if value]
        raise BatchError(f"{', '.join(named)}: TLS files are for a Dask cluster; give --scheduler tls://host:8786 too")
    if not address.strip():
        raise BatchError("--scheduler: the address is empty; give tcp://host:8786 or tls://host:8786, "
                         "or leave the option out to run on the local pool")
    if not address.startswith(SCHEMES):
        raise BatchError(f"--scheduler {address}: the address must start with tcp:// or tls:// "
                         "(tls:// with --tls-ca, --tls-cert and --tls-key for a cluster on a shared network)")
    if not address.startswith("tls://"):
        named = [option for option, value in given.items() if value]
        if named:
            raise BatchError(f"--scheduler {address}: {', '.join(named)} need a tls:// address")
        return None
    missing = [option for option, value in given.items() if not value]
    if missing:
        raise BatchError(f"--scheduler {address}: a TLS address needs {', '.join(missing)} "
                         "(the cluster's CA certificate, this client's certificate and its key, PEM files)")
    for option, value in given.items():
        if not Path(value).is_file():
            raise BatchError(f"{option} {value}: file not found")
    return TlsFiles(Path(ca), Path(cert), Path(key))


#: How long the client waits for the scheduler to answer.
CONNECT_TIMEOUT = "10s"


class DaskExecutor:
    """Runs on a Dask distributed cluster at ``address`` (a worker that dies is Dask's ``KilledWorker``).

    :meth:`connect` first, before anything of the batch is written: a scheduler that cannot
    be reached, or refuses this client, leaves nothing behind.
    """

    def __init__(self, address: str, tls: TlsFiles | None = None) -> None:
        self.address = address
        self.tls = tls
        self.client: Any = None  # distributed.Client once connected

    def connect(self) -> None:
        """Connect to the scheduler; ``BatchError`` (one line) when it cannot be reached or refuses."""
        from distributed import Client

        from orchestrator.batch_run import BatchError

        try:
            self.client = Client(self.address, timeout=CONNECT_TIMEOUT, set_as_default=False,
                                 security=self._security())
        except (OSError, TimeoutError, ValueError, TypeError) as exc:
            raise BatchError(f"cannot reach the Dask scheduler at {self.address}: {type(exc).__name__}: "
                             f"{exc}") from exc

    def close(self) -> None:
        """Close the connection (also when the batch ended before it ran)."""
        if self.client is not None:
            self.client.close()
            self.client = None

    def _security(self):
        if self.tls is None:
            return None
        from distributed.security import Security

        return Security(tls_ca_file=str(self.tls.ca), tls_client_cert=str(self.tls.cert),
                        tls_client_key=str(self.tls.key), require_encryption=True)

    def run(self, tasks: list) -> Iterator[tuple]:
        """Yield ``(task, record)`` as runs complete; closing the generator cancels the rest."""
        from distributed import CancelledError, KilledWorker, as_completed

        from orchestrator import interrupts
        from orchestrator.batch_run import WORKER_DIED, execute_run

        if self.client is None:
            self.connect()
        client = self.client
        futures = {}
        try:
            for task in tasks:
                future = client.submit(execute_run, task, key=f"rhnc-run-{task.run_id}-{os.urandom(4).hex()}",
                                       pure=False, retries=0)
                futures[future] = task
            for future in as_completed(futures, loop=client.loop):
                task = futures[future]
                try:
                    record = future.result()
                except KilledWorker:  # the cluster lost the worker (memory limit, node gone): redo on resume
                    record = {"status": "worker_died", "reason": f"{WORKER_DIED}: the Dask cluster lost it",
                              "infrastructure": True}
                except CancelledError:
                    continue
                except Exception as exc:  # e.g. the package is missing on the worker
                    record = {"status": "worker_died",
                              "reason": f"the worker could not run it: {type(exc).__name__}: {exc}"}
                yield task, record
        finally:
            if interrupts.stop_requested():
                interrupts.acknowledge()
            client.cancel(list(futures))
            self.close()
