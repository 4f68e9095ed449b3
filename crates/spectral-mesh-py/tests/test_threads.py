"""Threads, the GIL, Ctrl-C and panics."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

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


def run_script(script, *args, env=None, timeout=240):
    """Runs `script` in a fresh interpreter; a deadlock fails the test (timeout) instead of
    hanging the suite. Returns its stdout lines."""
    e = dict(os.environ)
    e.update(env or {})
    try:
        r = subprocess.run(
            [sys.executable, "-c", textwrap.dedent(script), *args],
            capture_output=True,
            text=True,
            timeout=timeout,
            env=e,
        )
    except subprocess.TimeoutExpired as err:
        raise AssertionError(f"no answer after {timeout} s: a deadlock?") from err
    assert r.returncode == 0, r.stderr
    return r.stdout.splitlines()


# Calls from several threads on one Analysis, mixed with calls on other meshes, many
# times: a computation whose worker waits in a parallel step must never pick up another
# call that waits for the lock it holds (the Analysis' solver). Running the work as a job
# of rayon's global pool (the main thread in the pool, as measured for the command line)
# deadlocked here within a few rounds.
CONCURRENT = """
    import threading
    import numpy as np
    import spectral_mesh as sm

    V, F = sm.shape("irregular-torus:res=4")
    V2, F2 = sm.shape("3torus")
    want_d = sm.Analysis(V, F).distance(3, k=40)
    want_w = sm.eigenbasis(V2, F2, 30)[0]
    for _ in range(6):
        an = sm.Analysis(V, F)
        out = {}
        calls = {
            "d": lambda: an.distance(3, k=40),
            "h": lambda: an.hks([0.1], k=40),
            "d2": lambda: an.distance(3, k=40),
            "w": lambda: sm.eigenbasis(V2, F2, 30)[0],
        }
        threads = [
            threading.Thread(target=lambda n=n, f=f: out.__setitem__(n, f()))
            for n, f in calls.items()
        ]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert np.array_equal(out["d"], want_d) and np.array_equal(out["d2"], want_d)
        assert np.array_equal(out["w"], want_w) and an.factorizations == 1
    print("ok")
"""


def test_concurrent_calls_on_one_analysis_never_deadlock():
    assert run_script(CONCURRENT) == ["ok"]


def test_a_progress_callback_can_call_the_package(torus):
    V, F = torus
    inner = []

    def progress(event):
        if event["stage"] == "factorization":
            # A computation started from the worker thread of another one.
            inner.append(sm.eigenbasis(*sm.shape("sphere:res=1"), 5)[0])

    w, _ = sm.eigenbasis(V, F, 20, method="shift-invert", progress=progress)
    assert len(inner) == 1 and inner[0].shape == (5,)
    assert np.array_equal(w, sm.eigenbasis(V, F, 20, method="shift-invert")[0])


def test_rayon_num_threads_sets_the_threads_of_a_computation():
    script = """
        import json
        import spectral_mesh as sm
        V, F = sm.shape("irregular-torus:res=3")
        w = sm.eigenbasis(V, F, 20)[0]
        print(sm.num_threads())
        print(json.dumps(w.tolist()))
    """
    one = run_script(script, env={"RAYON_NUM_THREADS": "1"}, timeout=120)
    two = run_script(script, env={"RAYON_NUM_THREADS": "2"}, timeout=120)
    assert one[0] == "1" and two[0] == "2"
    np.testing.assert_allclose(json.loads(one[1]), json.loads(two[1]), rtol=1e-9, atol=1e-12)


def test_the_allocator_setting_leaves_the_environment_as_it_was():
    script = """
        import os
        import spectral_mesh
        print(os.environ.get("MIMALLOC_PURGE_DELAY", "unset"))
    """
    assert run_script(script, timeout=60) == ["unset"]
    assert run_script(script, env={"MIMALLOC_PURGE_DELAY": "250"}, timeout=60) == ["250"]


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs /proc (Linux)")
def test_freed_memory_goes_back_to_the_system_soon_after_a_solve():
    script = """
        import time
        import spectral_mesh as sm
        def kib(key):
            for line in open("/proc/self/status"):
                if line.startswith(key):
                    return int(line.split()[1])
        V, F = sm.shape("sphere:res=5")
        tiny = sm.shape("sphere:res=1")
        sm.eigenbasis(*tiny, 3)
        time.sleep(0.1)
        sm.eigenbasis(*tiny, 3)  # what the start-up freed is purged before the baseline
        before = kib("VmRSS:")
        w, X = sm.eigenbasis(V, F, 100)
        time.sleep(0.1)
        sm.eigenbasis(*tiny, 3)  # the allocator at work again: it purges what is due
        print(kib("VmRSS:") - before, X.nbytes // 1024)
    """
    # The allocator's default (mimalloc v2: 10 ms) against a delay of 1 s (v3's default, so
    # that the buffers the solve freed are all still held): measured 9.5-9.6 MiB (8 runs)
    # against 63.7 (3 runs); the returned basis is 8 MiB of it. The call waits for its
    # pool's threads and its worker to end (src/run.rs); before it did, the same script
    # read anywhere from 9 to 62 MiB, as the threads happened to end before or after the
    # measurement.
    ours, basis = map(int, run_script(script, timeout=120)[0].split())
    kept, _ = map(int, run_script(script, env={"MIMALLOC_PURGE_DELAY": "1000"})[0].split())
    assert basis <= ours < 0.6 * kept, (ours, kept, basis)


def test_returned_arrays_own_their_data_in_the_documented_layout(torus):
    V, F = torus
    w, X = sm.eigenbasis(V, F, 12)
    assert w.dtype == np.float64 and w.shape == (12,) and w.flags.c_contiguous
    assert X.dtype == np.float64 and X.shape == (len(V), 12) and X.flags.f_contiguous
    assert w.flags.writeable and X.flags.writeable
    # The vectors are B-orthonormal columns, whatever the memory order.
    _, B = sm.laplacian(V, F)
    np.testing.assert_allclose(X.T @ (B @ X), np.eye(12), atol=1e-8)


@pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="needs /proc (Linux)")
def test_a_solve_leaves_no_thread_behind():
    # The module-level solves on a mesh of 4,096 vertices or more run on a thread pool made
    # for the call: its threads exit with it (and give their memory back), where the
    # global pool's would stay.
    script = """
        import os
        import time
        import spectral_mesh as sm
        V, F = sm.shape("sphere:res=5")
        assert len(V) >= 4096, len(V)
        # A thread that just ended (the worker of `shape`, joined) can still be listed for
        # a moment: the baseline is read once the list has settled.
        time.sleep(0.2)
        before = len(os.listdir("/proc/self/task"))
        sm.eigenbasis(V, F, 20)
        sm.laplacian(V, F)
        deadline = time.monotonic() + 10
        while len(os.listdir("/proc/self/task")) > before and time.monotonic() < deadline:
            time.sleep(0.01)
        print(before, len(os.listdir("/proc/self/task")))
    """
    out = run_script(script, env={"RAYON_NUM_THREADS": "2"}, timeout=60)
    before, after = map(int, out[0].split())
    assert after == before, (before, after)

