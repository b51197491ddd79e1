"""``study run --dask ADDRESS`` where ADDRESS is not a Dask scheduler: refused with the address and
what was expected, never a hang or an attempt to allocate what a stranger's first bytes announce."""
from __future__ import annotations

import http.server
import socket
import threading

import pytest

from cistrack.cli.main import main
from cistrack.errors import ConfigError
from cistrack.studies.execution import check_dask_scheduler

pytest.importorskip("distributed")

STUDY = """name = "tiny"
scenarios = ["quick"]
filters = [{ name = "pgm", n_particles = 300, n_components = 2 }]
iod = [{ name = "noisy-range", n_particles = 300 }]
seeds = [1]
[overrides]
duration_days = 1.4
"""


@pytest.fixture
def chatty_service():
    """The address of a TCP service that greets every connection with a line of text (like SSH)."""
    srv = socket.create_server(("127.0.0.1", 0))

    def serve():
        while True:
            try:
                conn, _ = srv.accept()
            except OSError:
                return
            with conn:
                conn.sendall(b"SSH-2.0-OpenSSH_9.6\r\nmore bytes than a length\r\n")

    threading.Thread(target=serve, daemon=True).start()
    yield f"tcp://127.0.0.1:{srv.getsockname()[1]}"
    srv.close()


@pytest.fixture
def http_server():
    """The address (HOST:PORT) of a plain HTTP server, which waits for a request and sends nothing first."""
    srv = http.server.ThreadingHTTPServer(("127.0.0.1", 0), http.server.SimpleHTTPRequestHandler)
    threading.Thread(target=srv.serve_forever, daemon=True).start()
    yield f"127.0.0.1:{srv.server_address[1]}"
    srv.shutdown()
    srv.server_close()


def test_study_run_refuses_a_service_that_greets_with_other_bytes(chatty_service, tmp_path, capsys):
    study = tmp_path / "tiny.toml"
    study.write_text(STUDY)
    assert main(["study", "run", str(study), "--out", str(tmp_path / "s"), "--dask", chatty_service, "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f"--dask {chatty_service}: what answers at" in err and "is not a Dask scheduler" in err
    assert "give the address of a Dask scheduler" in err and "Traceback" not in err
    assert not (tmp_path / "s" / "runs").exists()


def test_an_http_server_that_sends_nothing_is_refused_when_the_greeting_times_out(http_server):
    with pytest.raises(ConfigError, match=rf"--dask {http_server}: .* not a Dask scheduler: it sent nothing "
                                          r"within 0.5 s .*HTTP server"):
        check_dask_scheduler(http_server, timeout_s=0.5)


def test_an_address_where_nothing_listens_is_refused_naming_it():
    with socket.create_server(("127.0.0.1", 0)) as s:
        port = s.getsockname()[1]
    with pytest.raises(ConfigError, match=rf"--dask tcp://127.0.0.1:{port}: cannot connect to 127.0.0.1:{port}"):
        check_dask_scheduler(f"tcp://127.0.0.1:{port}", timeout_s=2)


@pytest.mark.parametrize("address", ["tcp://127.0.0.1:99999", "tcp://127.0.0.1:x", "::1:8786", "tcp://:8786"])
def test_a_malformed_address_is_refused_saying_what_an_address_is(address):
    with pytest.raises(ConfigError, match=r"not an address: give tcp://HOST:PORT"):
        check_dask_scheduler(address)


def test_a_real_scheduler_passes_the_check():
    from distributed import LocalCluster

    with LocalCluster(n_workers=0, processes=True, dashboard_address=None, host="127.0.0.1") as cluster:
        check_dask_scheduler(cluster.scheduler_address)
        check_dask_scheduler(cluster.scheduler_address.removeprefix("tcp://"))


def test_the_check_leaves_other_transports_to_dask():
    assert check_dask_scheduler("ucx://127.0.0.1:1", timeout_s=0.1) is None  # nothing listens; Dask will say so
