"""`study` on Dask as a good citizen: a foreign --scheduler is one line, no lock from a failed
start, no dashboard unless asked, the refusal of a reused --out names what differs, and a
Ctrl-C is one line (docs/study.md)."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading

import pytest

from slipreflex.cli import main
from slipreflex.study import cluster, runner

TINY = ["--plants", "2", "--trials", "1", "--bottles", "TX", "--methods", "dath", "--experiments", "drop",
        "--no-calibration", "--no-figures", "--no-progress"]


class _Server:
    """A TCP server that is not a Dask scheduler: it sends ``banner`` (or nothing) and waits."""

    def __init__(self, banner: bytes):
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.address = f"tcp://127.0.0.1:{self.sock.getsockname()[1]}"
        self.banner = banner
        self.conns = []
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self):
        while True:
            try:
                conn, _ = self.sock.accept()
            except OSError:
                return
            self.conns.append(conn)
            if self.banner:
                conn.sendall(self.banner)

    def close(self):
        for c in self.conns:
            c.close()
        self.sock.close()


@pytest.mark.parametrize("banner, says", [(b"SSH-2.0-OpenSSH_9.2p1 Debian\r\n", "not as a Dask scheduler"),
                                          (b"", "no Dask handshake within 0.5 s")])
def test_a_scheduler_that_is_not_dask_is_one_line_and_leaves_no_lock(tmp_path, capsys, monkeypatch,
                                                                       banner, says):
    monkeypatch.setattr(cluster, "SCHEDULER_TIMEOUT_S", 0.5)
    server = _Server(banner)
    try:
        out = tmp_path / "out"
        assert main(["study", *TINY, "--scheduler", server.address, "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert says in err and len(err.strip().splitlines()) == 1, err
        assert not out.exists()                  # no study.json locking --out, no folder left
        out.mkdir()
        (out / "keep.txt").write_text("mine")
        assert main(["study", *TINY, "--scheduler", server.address, "--out", str(out)]) == 2
        capsys.readouterr()
        assert sorted(os.listdir(out)) == ["keep.txt"]
    finally:
        server.close()


def test_a_closed_port_is_one_line(tmp_path, capsys):
    s = socket.create_server(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    assert main(["study", *TINY, "--scheduler", f"tcp://127.0.0.1:{port}", "--out", str(tmp_path / "o")]) == 2
    assert "cannot connect" in capsys.readouterr().err and not (tmp_path / "o").exists()


def test_the_local_cluster_listens_on_loopback_without_a_dashboard(monkeypatch):
    import dask.distributed as dd

    seen = {}

    class Cluster:
        def __init__(self, **kw):
            seen.update(kw)
            seen["sigint_blocked"] = signal.SIGINT in signal.pthread_sigmask(signal.SIG_BLOCK, set())
            seen["sigint_ignored"] = signal.getsignal(signal.SIGINT) is signal.SIG_IGN

    monkeypatch.setattr(dd, "LocalCluster", Cluster)
    monkeypatch.setattr(dd, "Client", lambda cluster: None)
    runner._client(1, None)
    assert seen["host"] == "127.0.0.1" and seen["dashboard_address"] is None and seen["sigint_blocked"]
    assert seen["sigint_ignored"] and signal.getsignal(signal.SIGINT) is not signal.SIG_IGN
    assert signal.SIGINT not in signal.pthread_sigmask(signal.SIG_BLOCK, set())   # unblocked again
    # its health page on a free loopback port: two studies at once do not both try 8787
    assert seen["scheduler_kwargs"] == {"dashboard": False, "dashboard_address": "127.0.0.1:0"}
    runner._client(1, None, "127.0.0.1:0")
    assert seen["dashboard_address"] == "127.0.0.1:0" and seen["scheduler_kwargs"] == {}


@pytest.mark.slow
def test_a_local_cluster_starts_quietly_while_port_8787_is_taken():
    try:
        held = socket.create_server(("127.0.0.1", 8787))
    except OSError:           # taken already: what the test needs
        held = None
    try:
        client, cluster, _ = runner._client(1, None)   # warnings are errors here, a leaked socket too
        with client, cluster:
            page = cluster.scheduler.http_server
            assert client.submit(sum, [1, 2]).result() == 3
            assert page.address == "127.0.0.1" and page.port != 8787
    finally:
        if held is not None:
            held.close()


def test_a_reused_out_names_the_arguments_that_differ(tmp_path, capsys, monkeypatch):
    from slipreflex.study import StudyConfig

    monkeypatch.setattr(runner, "run_plant", lambda *a, **k: pytest.fail("work started"))
    out = tmp_path / "o"
    cfg = StudyConfig(plants=2, trials=1, bottles=("TX",), methods=("dath",), experiments=("drop",),
                      calibrate=False)
    assert runner._check_out(out, cfg) is True                 # what a first run records
    assert runner._check_out(out, cfg) is False                # the same study: resumed
    args = [*TINY, "--workers", "0", "--out", str(out)]
    args[args.index("--plants") + 1] = "4"
    assert main(["study", *args, "--seed", "7"]) == 2
    err = capsys.readouterr().err
    assert "--plants 4 (the study there: 2)" in err and "--seed 7" in err and "fingerprint" not in err
    assert len(err.strip().splitlines()) == 1


@pytest.mark.slow
def test_ctrl_c_of_a_local_cluster_study_is_one_line(tmp_path):
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen([sys.executable, "-m", "slipreflex", "study", *TINY[:-1], "--plants", "8",
                             "--workers", "1", "--out", str(tmp_path / "o")],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            start_new_session=True)
    killer = threading.Timer(240, lambda: os.killpg(proc.pid, signal.SIGKILL))
    killer.start()
    try:
        for line in proc.stderr:                # the progress line: the cluster is up, plants run
            if "plants" in line:
                break
        os.killpg(proc.pid, signal.SIGINT)      # as a terminal does: the whole process group
        out, err = proc.communicate(timeout=120)
    finally:
        killer.cancel()
    lines = [x for x in err.splitlines() if x.strip() and "plants" not in x]
    assert proc.returncode == 130, err
    assert len(lines) == 1 and "interrupted" in lines[0], err
    assert "Traceback" not in err
