"""Runs release the GIL and stop on Ctrl-C: measured, in one process, on the CI's 2 cores.

These tests time things; the figures they print (`pytest -s`) are the ones quoted in
docs/python.md."""

from __future__ import annotations

import os
import signal
import statistics
import threading
import time

import pytest

import tissue

SHORT = dict(max_steps=150)


@pytest.fixture(scope="module")
def table2() -> tissue.Patient:
    return tissue.Patient.shipped("table2")


def test_other_python_threads_run_while_a_plan_runs(table2: tissue.Patient) -> None:
    """The GIL is released during a run: a pure-Python counter on another thread keeps
    counting while the main thread plans (with the GIL held it would stop)."""
    stop = threading.Event()
    count = [0]

    def counter() -> None:
        while not stop.is_set():
            count[0] += 1

    t = threading.Thread(target=counter)
    t.start()
    try:
        time.sleep(0.05)
        before = count[0]
        start = time.perf_counter()
        tissue.plan(table2, **SHORT)
        seconds = time.perf_counter() - start
        during = count[0] - before
    finally:
        stop.set()
        t.join()
    # A counting thread alone does millions of increments a second; with the GIL held by the
    # run it would get only the 20 ms slices the waiting thread leaves it.
    print(f"\ncounter: {during / seconds:.0f} increments/s during a {seconds:.2f} s run")
    assert during / seconds > 10_000


def test_two_threads_planning_at_once_beat_one_after_the_other(table2: tissue.Patient) -> None:
    """Two threads plan at once: their runs overlap in time (with the GIL held they could not:
    the second would wait for the first), and on free cores they take clearly less than one
    after the other."""
    spans: dict = {}

    def one(key: object = None) -> None:
        steps = []
        tissue.plan(table2, progress=lambda s, m, _: steps.append(time.perf_counter()), **SHORT)
        if key is not None:
            spans[key] = (steps[0], steps[-1])

    def sequential() -> float:
        start = time.perf_counter()
        one()
        one()
        return time.perf_counter() - start

    def together() -> float:
        threads = [threading.Thread(target=one, args=(i,)) for i in range(2)]
        start = time.perf_counter()
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        return time.perf_counter() - start

    one()  # warm up (the thread pools, the page cache)
    seq, par, overlaps = [], [], []
    for _ in range(5):  # alternated, medians: the machine is shared
        seq.append(sequential())
        par.append(together())
        (a0, a1), (b0, b1) = spans[0], spans[1]
        overlaps.append((min(a1, b1) - max(a0, b0)) / min(a1 - a0, b1 - b0))
    s, p = statistics.median(seq), statistics.median(par)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else 0.0
    cores = os.cpu_count() or 1
    print(
        f"\ntwo short Table 2 runs: one after the other {s:.3f} s, at once {p:.3f} s, ratio "
        f"{p / s:.2f}; the runs' stepping overlapped {statistics.median(overlaps):.0%} "
        f"(load average {load:.1f} on {cores} cores)"
    )
    # Both runs step at the same time: most of the shorter one lies within the other.
    assert statistics.median(overlaps) > 0.5, overlaps
    # The speed-up needs cores to spare: on 2 idle cores about 0.7 (each run also uses rayon);
    # a machine already busy with other work gives none, whatever the GIL does.
    if load < cores - 0.5:
        assert p < 0.9 * s, (seq, par)


def test_ctrl_c_cancels_a_long_run_within_100_ms(table2: tissue.Patient) -> None:
    """SIGINT from a timer thread during a run that would take a minute: KeyboardInterrupt is
    raised within 100 ms (+ a margin for a loaded machine) of the signal."""
    if threading.current_thread() is not threading.main_thread():  # pragma: no cover
        pytest.skip("signals reach the main thread only")
    sent = []

    def interrupt() -> None:
        sent.append(time.perf_counter())
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(0.5, interrupt)
    start = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        # A time step so small that the run never settles: 20 000 steps, about a minute.
        tissue.plan(table2, time_step_s=1e-6, max_steps=20000)
    caught = time.perf_counter()
    timer.join()
    latency = caught - sent[0]
    print(f"\nCtrl-C: KeyboardInterrupt {latency * 1e3:.1f} ms after SIGINT ({caught - start:.2f} s into the run)")
    assert latency < 0.1 + 0.05
    # The package still works: the cancelled run's thread stopped on its own.
    assert tissue.plan(table2, max_steps=10).report["steps"] == 10


def test_ctrl_c_during_a_sweep_also_cancels(table2: tissue.Patient) -> None:
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    start = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        tissue.sweep(table2, [50, 100], time_step_s=1e-6, max_steps=20000)
    timer.join()
    assert time.perf_counter() - start < 0.3 + 0.2
