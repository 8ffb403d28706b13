"""Campaigns that cannot corrupt their results: a second campaign into a locked folder, a
rerun (resumes), `--retry-failed`, duplicates of an older campaign, a port that is not Dask's
(a real HTTP server, a banner, silence), refused arguments and output locations, a row that
cannot be written. Each case ends in one line and exit 2, or in a complete results.csv with one
row per run. The campaigns share one LocalCluster on 127.0.0.1 through `--scheduler`."""

from __future__ import annotations

import csv
import errno
import http.server
import socket
import threading
import time

import pytest

from drake_auv.campaign import ResultsFile, connect, probe_scheduler
from drake_auv.cli import main

SHORT = ["--set", "limits.max_time_s=8"]


@pytest.fixture(scope="module")
def scheduler():
    """The address of a real Dask scheduler (a LocalCluster of 2 workers, 127.0.0.1 only)."""
    client, cluster = connect(workers=2)
    client.wait_for_workers(2, timeout=60)
    yield cluster.scheduler_address, client
    client.close()
    cluster.close()


def _campaign(out, scheduler, *extra):
    return main(["campaign", "breakwater", *SHORT, "--scheduler", scheduler[0], "--quiet",
                 "-o", str(out), *extra])


def _rows(out) -> list[dict]:
    with open(out / "results.csv", newline="") as f:
        return list(csv.DictReader(f))


def _one_line(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    return err


def test_a_second_campaign_into_a_running_ones_folder_exits_2(tmp_path, scheduler, capsys):
    out = tmp_path / "out"
    codes, same = [], ("--seeds", "0:4", "--set", "limits.max_time_s=20")
    first = threading.Thread(target=lambda: codes.append(_campaign(out, scheduler, *same)))
    first.start()
    deadline = time.monotonic() + 60
    while not (out / "results.csv").exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    assert first.is_alive()
    assert _campaign(out, scheduler, *same) == 2
    assert "another campaign is running into this folder" in _one_line(capsys)
    first.join(timeout=300)
    assert codes == [0]
    rows = _rows(out)
    assert sorted(r["seed"] for r in rows) == ["0", "1", "2", "3"]
    assert all(r["status"] == "ok" for r in rows)
    assert "Seeds 0..3 (4 seeds); 4 runs (0 failed)" in (out / "summary.md").read_text()
    # The lock is released with the campaign: a rerun resumes (nothing missing, nothing run).
    assert _campaign(out, scheduler, *same) == 0
    assert "4 runs (4 already in results.csv" in capsys.readouterr().out
    assert len(_rows(out)) == 4


def test_rerun_resumes_retry_failed_replaces_and_duplicates_are_compacted(tmp_path, scheduler,
                                                                          capsys):
    out = tmp_path / "out"
    out.mkdir()
    results = ResultsFile(out / "results.csv", [])
    results.append(("1",), dict(status="failed", error="KilledWorker: Attempted to run task"))
    results.append(("2",), dict(status="ok", coverage_multibeam=0.5, contact=False))
    with open(out / "results.csv") as f:
        twice = f.readlines()[-1]
    with open(out / "results.csv", "a") as f:  # what two unlocked campaigns used to write
        f.write(twice)
    assert _campaign(out, scheduler, "--seeds", "0:3") == 0
    assert "3 runs (2 already in results.csv, 0 failed ones run again, 1 ok" in \
        capsys.readouterr().out
    rows = {r["seed"]: r for r in _rows(out)}
    assert len(_rows(out)) == 3 and rows["1"]["status"] == "failed"
    assert _campaign(out, scheduler, "--seeds", "0:3", "--retry-failed") == 0
    assert "1 failed ones run again, 1 ok" in capsys.readouterr().out
    rows = _rows(out)
    assert sorted(r["seed"] for r in rows) == ["0", "1", "2"]
    assert all(r["status"] == "ok" for r in rows)
    summary = (out / "summary.md").read_text()
    assert "3 runs (0 failed)" in summary
    assert sum("all" in line for line in summary.splitlines() if line.startswith("|")) == 1


class _Quiet(http.server.BaseHTTPRequestHandler):
    def log_message(self, *args):
        pass


def _tcp_server(greeting: bytes | None):
    """A TCP server on 127.0.0.1 that sends `greeting` (None: nothing) to each connection and
    reads until the client leaves; returns (port, stop)."""
    listener = socket.create_server(("127.0.0.1", 0))
    listener.settimeout(0.2)
    stop = threading.Event()

    def serve():
        while not stop.is_set():
            try:
                conn, _ = listener.accept()
            except TimeoutError:
                continue
            with conn:
                if greeting:
                    conn.sendall(greeting)
                conn.settimeout(0.2)
                while not stop.is_set():
                    try:
                        if not conn.recv(65536):
                            break
                    except TimeoutError:
                        continue
                    except OSError:
                        break
        listener.close()

    threading.Thread(target=serve, daemon=True).start()
    return listener.getsockname()[1], stop.set


@pytest.mark.parametrize("kind", ["http", "banner", "silent"])
def test_a_port_that_is_not_dask_is_one_line_within_the_timeout(kind, tmp_path, capsys,
                                                                monkeypatch):
    monkeypatch.setattr("drake_auv.campaign.engine.CONNECT_TIMEOUT_S", 2.0)
    if kind == "http":
        server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), _Quiet)
        threading.Thread(target=server.serve_forever, daemon=True).start()
        port, stop = server.server_address[1], server.shutdown
    else:
        port, stop = _tcp_server(b"SSH-2.0-OpenSSH_9.2p1 Debian-2\r\n" if kind == "banner"
                                 else None)
    try:
        start = time.monotonic()
        code = main(["campaign", "breakwater", "--seeds", "0:2", "--scheduler",
                     f"tcp://127.0.0.1:{port}", "-o", str(tmp_path / "out")])
        elapsed = time.monotonic() - start
    finally:
        stop()
    assert code == 2 and elapsed < 15
    assert f"cannot reach the Dask scheduler at tcp://127.0.0.1:{port}" in _one_line(capsys)
    assert not (tmp_path / "out").exists()  # nothing written


def test_a_real_scheduler_answers_the_probe(scheduler):
    assert probe_scheduler(scheduler[0])["type"] == "Scheduler"


def test_refused_arguments_write_nothing(tmp_path, capsys):
    out = tmp_path / "out"
    for argv, message in ((["--workers", "0"], "--workers 0: this machine has"),
                          (["--workers", "1000"], "allowed: an integer in [1, "),
                          (["--vary", "site.bogus=1,2"], "site.bogus: unknown key"),
                          (["--seeds", "3:1"], "--seeds: '3:1' is empty")):
        assert main(["campaign", "breakwater", "--seeds", "0:2", *argv, "-o", str(out)]) == 2
        assert message in _one_line(capsys)
        assert not out.exists()


def test_output_in_the_way_is_refused_before_any_task(tmp_path, scheduler, capsys):
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    folder_in_the_way = tmp_path / "held"
    (folder_in_the_way / "results.csv").mkdir(parents=True)
    for out, message in ((a_file, "is a file, not a folder"),
                         (a_file / "sub", f"{a_file} is a file, not a folder"),
                         (folder_in_the_way, "results.csv is a folder, not a file")):
        assert _campaign(out, scheduler, "--seeds", "0:2") == 2
        assert message in _one_line(capsys)
    assert a_file.read_text() == "x"
    assert sorted(p.name for p in folder_in_the_way.iterdir()) == ["results.csv"]
    assert scheduler[1].run_on_scheduler(lambda dask_scheduler: len(dask_scheduler.tasks)) \
        == 0


def test_a_row_that_cannot_be_written_stops_the_campaign_rows_kept(tmp_path, scheduler,
                                                                   capsys, monkeypatch):
    out = tmp_path / "out"
    append = ResultsFile.append
    written = []

    def full_disk_after_one_row(self, key, row):
        if written:
            raise OSError(errno.ENOSPC, "No space left on device", str(self.path))
        written.append(key)
        append(self, key, row)

    monkeypatch.setattr(ResultsFile, "append", full_disk_after_one_row)
    assert _campaign(out, scheduler, "--seeds", "0:4") == 2
    err = _one_line(capsys)
    assert "results.csv: cannot write the row of run" in err and "No space left" in err
    assert "1 row(s) written now kept, 3 run(s) not written" in err
    assert len(_rows(out)) == 1
    client = scheduler[1]
    deadline = time.monotonic() + 20
    while client.run_on_scheduler(lambda dask_scheduler: len(dask_scheduler.tasks)) and \
            time.monotonic() < deadline:
        time.sleep(0.1)
    assert client.run_on_scheduler(lambda dask_scheduler: len(dask_scheduler.tasks)) == 0
    monkeypatch.setattr(ResultsFile, "append", append)
    assert _campaign(out, scheduler, "--seeds", "0:4") == 0  # the rerun runs the other three
    assert "4 runs (1 already in results.csv" in capsys.readouterr().out
    assert sorted(r["seed"] for r in _rows(out)) == ["0", "1", "2", "3"]
