"""The machine's cores: chunked inner loops on worker threads, in order, the GC kept off them;
a batch program's tuning."""

import gc
import threading

import numpy as np
import pytest

from drake_auv import resources
from drake_auv.resources import map_chunks


def test_chunks_come_back_in_order_whatever_the_cores(monkeypatch):
    values = np.arange(1000.0)
    parallel = map_chunks(lambda s: values[s] ** 2, len(values), 64)
    monkeypatch.setattr(resources, "usable_cores", lambda: 1)
    serial = map_chunks(lambda s: values[s] ** 2, len(values), 64)
    assert len(parallel) == 16
    np.testing.assert_array_equal(np.concatenate(parallel), values ** 2)
    np.testing.assert_array_equal(np.concatenate(serial), values ** 2)
    assert map_chunks(lambda s: s, 0, 64) == []


def test_workers_run_with_the_collector_paused_and_do_not_nest(monkeypatch):
    monkeypatch.setattr(resources, "usable_cores", lambda: 2)
    seen = []

    def chunk(s):
        inner = map_chunks(lambda t: threading.current_thread().name, 4, 1)
        seen.append((threading.current_thread().name, gc.isenabled(), inner))
        return s.start

    assert gc.isenabled()
    assert map_chunks(chunk, 6, 2) == [0, 2, 4]
    assert gc.isenabled()
    assert any(name.startswith("drake_auv-chunks") for name, _, _ in seen)
    for name, enabled, inner in seen:
        assert not enabled
        assert inner == [name] * 4  # a worker's own chunks run on it, in turn


def test_pauses_nest_and_overlap_across_threads():
    from drake_auv.resources import paused_gc

    outer = paused_gc().__enter__()
    inner = paused_gc().__enter__()
    assert not gc.isenabled()
    outer.__exit__(None, None, None)  # the first pause ends before the second
    assert not gc.isenabled()
    inner.__exit__(None, None, None)
    assert gc.isenabled()


def test_only_the_plan_command_asks_for_the_batch_process_tuning():
    from drake_auv.cli import build_parser

    parser = build_parser()
    assert parser.parse_args(["plan", "site.tif", "-o", "out"]).batch_process is True
    assert not getattr(parser.parse_args(["run", "pool", "-o", "out"]), "batch_process",
                       False)


def test_quick_gil_handoff_shortens_the_switch_interval():
    import sys

    from drake_auv.resources import quick_gil_handoff

    before = sys.getswitchinterval()
    try:
        quick_gil_handoff(0.0007)
        assert sys.getswitchinterval() == pytest.approx(0.0007)
    finally:
        sys.setswitchinterval(before)
