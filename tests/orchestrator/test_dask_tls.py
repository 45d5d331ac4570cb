"""Batches on a Dask cluster with TLS, and one-line errors for scheduler addresses that cannot work."""

import pandas as pd
import pytest

from orchestrator.batch import NONDETERMINISTIC_COLUMNS, run_batch
from orchestrator.cli import main


@pytest.fixture
def tls_files(tmp_path):
    """A throw-away CA-signed certificate (Dask's own generator) as PEM files, and its Security."""
    from distributed.security import Security

    security = Security.temporary()
    files = {}
    for name, content in (("ca", security.tls_ca_file), ("cert", security.tls_client_cert),
                          ("key", security.tls_client_key)):
        files[name] = tmp_path / f"{name}.pem"
        files[name].write_text(content)
    return security, files


@pytest.mark.slow
def test_a_batch_on_a_tls_cluster_gives_the_local_table(small_batch, tmp_path, tls_files, capsys):
    from distributed import LocalCluster

    security, files = tls_files
    local = run_batch(small_batch, tmp_path / "local", workers=1, progress=False)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, protocol="tls://", host="127.0.0.1",
                      security=security, dashboard_address=None) as cluster:
        address = cluster.scheduler_address
        assert address.startswith("tls://127.0.0.1:")
        code = main(["batch", str(small_batch), "--results", str(tmp_path / "tls"), "--no-progress",
                     "--scheduler", address, "--tls-ca", str(files["ca"]), "--tls-cert", str(files["cert"]),
                     "--tls-key", str(files["key"])])
    assert code == (0 if local.passed == local.total else 3)
    table = pd.read_parquet(tmp_path / "tls" / "small" / "summary.parquet")

    def comparable(frame):
        return frame.drop(columns=list(NONDETERMINISTIC_COLUMNS)).sort_values("run_id").reset_index(drop=True)

    pd.testing.assert_frame_equal(comparable(table), comparable(local.table))


@pytest.mark.parametrize("args, message", [
    (["--scheduler", ""], "error: --scheduler: the address is empty; give tcp://host:8786 or tls://host:8786, "
                          "or leave the option out to run on the local pool"),
    (["--scheduler", "tls://10.0.0.5:8786"],
     "error: --scheduler tls://10.0.0.5:8786: a TLS address needs --tls-ca, --tls-cert, --tls-key (the cluster's "
     "CA certificate, this client's certificate and its key, PEM files)"),
    (["--scheduler", "tls://10.0.0.5:8786", "--tls-ca", "ca.pem"],
     "error: --scheduler tls://10.0.0.5:8786: a TLS address needs --tls-cert, --tls-key (the cluster's "
     "CA certificate, this client's certificate and its key, PEM files)"),
    (["--scheduler", "tcp://10.0.0.5:8786", "--tls-cert", "cert.pem"],
     "error: --scheduler tcp://10.0.0.5:8786: --tls-cert need a tls:// address"),
    (["--scheduler", "10.0.0.5:8786"],
     "error: --scheduler 10.0.0.5:8786: the address must start with tcp:// or tls:// (tls:// with --tls-ca, "
     "--tls-cert and --tls-key for a cluster on a shared network)"),
    (["--tls-ca", "ca.pem"], "error: --tls-ca: TLS files are for a Dask cluster; give --scheduler tls://host:8786 too"),
    (["--scheduler", "tls://10.0.0.5:8786", "--tls-ca", "missing.pem", "--tls-cert", "c", "--tls-key", "k"],
     "error: --tls-ca missing.pem: file not found"),
])
def test_a_scheduler_that_cannot_work_is_one_line_and_writes_nothing(small_batch, tmp_path, capsys, args, message):
    code = main(["batch", str(small_batch), "--results", str(tmp_path / "results"), "--no-progress", *args])
    assert code == 2
    assert capsys.readouterr().err.strip().splitlines() == [message]
    assert not (tmp_path / "results").exists()


def test_a_scheduler_that_cannot_be_reached_leaves_nothing(small_batch, tmp_path, capsys, monkeypatch):
    """Refused before anything of the batch is written: no batch.json, lock or empty runs/."""
    import socket

    from orchestrator import dask_executor

    monkeypatch.setattr(dask_executor, "CONNECT_TIMEOUT", "1s")
    with socket.socket() as probe:  # a port nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    code = main(["batch", str(small_batch), "--results", str(tmp_path / "results"), "--no-progress",
                 "--scheduler", f"tcp://127.0.0.1:{port}"])
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"error: cannot reach the Dask scheduler at tcp://127.0.0.1:{port}: ")
    assert not (tmp_path / "results").exists()
