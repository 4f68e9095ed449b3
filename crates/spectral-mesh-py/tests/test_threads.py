"""Threads, the GIL, Ctrl-C and panics."""

from __future__ import annotations

import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest

import spectral_mesh as sm


def run_in_threads(calls):
    """Runs the callables at once, one thread each, and returns their results."""
    results = [None] * len(calls)
    errors = []
    barrier = threading.Barrier(len(calls))

    def work(i, f):
        try:
            barrier.wait()
            results[i] = f()
        except BaseException as e:  # noqa: BLE001 - reported below
            errors.append(e)

    threads = [threading.Thread(target=work, args=(i, f)) for i, f in enumerate(calls)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    if errors:
        raise errors[0]
    return results


def test_two_threads_give_the_results_of_one_after_the_other(torus, pretzel):
    V1, F1 = torus
    V2, F2 = pretzel
    seq = [sm.eigenbasis(V1, F1, 40), sm.eigenbasis(V2, F2, 40)]
    par = run_in_threads([lambda: sm.eigenbasis(V1, F1, 40), lambda: sm.eigenbasis(V2, F2, 40)])
    for (w, X), (w2, X2) in zip(seq, par, strict=True):
        assert np.array_equal(w, w2) and np.array_equal(X, X2)


def test_two_threads_on_one_analysis(pretzel):
    V, F = pretzel
    ref = sm.Analysis(V, F)
    want = [ref.distance(5, k=60), ref.hks([0.01, 0.1], k=60), ref.harmonic(4), ref.heat(9, k=60)]
    an = sm.Analysis(V, F)
    got = run_in_threads(
        [
            lambda: an.distance(5, k=60),
            lambda: an.hks([0.01, 0.1], k=60),
            lambda: an.harmonic(4),
            lambda: an.heat(9, k=60),
        ]
    )
    for a, b in zip(want, got, strict=True):
        assert np.array_equal(a, b)
    # One basis served every spectral request: the threads waited for the one solve.
    # (Requests with a smaller k than the basis held use its first k pairs, which agree
    # with a solve for that k to the solver's tolerance, not bit for bit: the same
    # requests in another order may differ at round-off level when their k differ.)
    assert an.factorizations == 1 and an.held_k == 60


def test_the_gil_is_released_during_a_solve():
    V, F = sm.shape("sphere:res=5")  # 10242 vertices
    done = threading.Event()
    duration = []

    def solve():
        t0 = time.perf_counter()
        sm.eigenbasis(V, F, 150)
        duration.append(time.perf_counter() - t0)
        done.set()

    t = threading.Thread(target=solve)
    stamps = []
    t.start()
    while not done.is_set():
        stamps.append(time.perf_counter())
        sum(range(2000))  # pure-Python work that needs the GIL
    t.join()
    gaps = np.diff(stamps)
    # Had the solve held the GIL, this loop would have stalled for its whole duration.
    assert len(stamps) > 100
    assert gaps.max() < 0.5 * duration[0], (gaps.max(), duration[0])


CTRL_C = textwrap.dedent(
    """
    import os, signal, sys, threading, time
    # A parent that ignores SIGINT (a shell's background job) passes that on, and Python
    # then raises no KeyboardInterrupt: take Python's own handler back.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    import spectral_mesh as sm
    what = sys.argv[1]
    if what == "solve":
        V, F = sm.shape("sphere:res=6")  # 40962 vertices: k = 400 takes many seconds
        call = lambda: sm.eigenbasis(V, F, 400)
    else:
        call = lambda: sm._native._work_for_tests(30.0, what == "checks")
    sent = []
    def interrupt():
        time.sleep(1.5)
        sent.append(time.perf_counter())
        os.kill(os.getpid(), signal.SIGINT)
    threading.Thread(target=interrupt, daemon=True).start()
    try:
        call()
        print("finished")
    except KeyboardInterrupt:
        print(f"interrupted after {time.perf_counter() - sent[0]:.3f}")
    # The package still works after an interruption.
    print(sm.eigenbasis(*sm.shape("sphere:res=1"), 5)[0].shape)
    """
)


@pytest.mark.parametrize("what", ["checks", "ignores", "solve"])
def test_ctrl_c_stops_a_computation_within_a_second(what):
    r = subprocess.run(
        [sys.executable, "-c", CTRL_C, what], capture_output=True, text=True, timeout=300
    )
    assert r.returncode == 0, r.stderr
    lines = r.stdout.split("\n")
    assert lines[0].startswith("interrupted after"), r.stdout
    latency = float(lines[0].split()[-1])
    assert latency < 1.0, latency
    assert lines[1] == "(5,)"


def test_a_panic_becomes_an_exception():
    with pytest.raises(sm.InternalError, match="internal error in spectral-mesh.*boom") as e:
        sm._native._panic_for_tests("boom")
    assert isinstance(e.value, RuntimeError)
    # The interpreter and the package go on.
    assert sm.eigenbasis(*sm.shape("sphere:res=1"), 3)[0].shape == (3,)


def test_cancellable_work_is_not_interrupted_without_a_signal():
    assert sm._native._work_for_tests(0.2, True) >= 0.2


def test_progress_callbacks(torus):
    V, F = torus
    events = []
    w, X = sm.eigenbasis(V, F, 30, method="shift-invert", progress=events.append)
    stages = [e["stage"] for e in events]
    assert stages[0] == "factorization" and stages[-1] == "finished" and "iteration" in stages
    assert events[-1]["max_residual"] <= 1e-10
    it = [e for e in events if e["stage"] == "iteration"]
    # The torus is connected: its constant vector (eigenvalue 0) is deflated exactly and
    # returned first, so the iteration looks for the other 29 pairs.
    assert it[-1]["wanted"] == 29 and all(e["converged"] <= 29 for e in it)
    # Same pairs as without a callback.
    assert np.array_equal(w, sm.eigenbasis(V, F, 30, method="shift-invert")[0])
    an = sm.Analysis(V, F)
    seen = []
    an.basis(20, progress=seen.append)
    assert seen and seen[-1]["stage"] == "finished"

    # An exception in the callback is raised by the call (the solve stops, or its result
    # is dropped when the solver does not check in time).
    class Stop(Exception):
        pass

    def stop(event):
        if event["stage"] == "iteration":
            raise Stop("enough")

    with pytest.raises(Stop, match="enough"):
        sm.eigenbasis(V, F, 40, method="shift-invert", progress=stop)
    with pytest.raises(Stop):
        sm.eigsh(
            *sm.laplacian(V, F)[:1],
            10,
            sm.laplacian(V, F)[1],
            sigma=-0.01,
            method="shift-invert",
            progress=stop,
        )
    assert sm.eigenbasis(V, F, 5)[0].shape == (5,)
