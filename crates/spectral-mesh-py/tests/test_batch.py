"""spectral_mesh.batch: a local process pool and a local Dask cluster (a scheduler and two
worker processes on 127.0.0.1, no dashboard) with one worker killed mid-run; the outputs
equal a local run's bit for bit; reruns do no work; an edited input recomputes exactly
that shape."""

from __future__ import annotations

import csv
import os
import shutil
import signal
import threading
import time
from pathlib import Path

import pytest

import spectral_mesh as sm
from conftest import shared_dir

SHARED = ["cow.off", "elephant.off", "hand.off", "knot1.off", "homer.off", "cactus.off"]
BROKEN = {
    "bad-index.off": ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n", "9"),
    "empty.off": ("", "empty.off"),
    "words.obj": ("this is not a mesh\n", "words.obj"),
}
PARAMS = dict(k=20, hks="auto:4", wks=3)


def make_set(root: Path, shared: Path | None, generated: int) -> Path:
    """Shared meshes (when the folder is given), generated ones, and broken files."""
    src = root / "set"
    src.mkdir()
    if shared is not None:
        for name in SHARED:
            shutil.copy(shared / name, src / name)
    for i in range(generated):
        V, F = sm.shape(f"torus:res=3,R={1.2 + 0.1 * i},r=0.4")
        sm.write_mesh(src / f"gen{i}.off", V, F)
    for name, (text, _) in BROKEN.items():
        (src / name).write_text(text)
    return src


def results(out: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(out.glob("*.npz"))}


def by_name(records):
    return {r["name"]: r for r in records}


def check_rows(records, src: Path, out: Path):
    rows = by_name(records)
    assert set(rows) == {p.name for p in src.iterdir()}
    for name, (_, reason) in BROKEN.items():
        r = rows[name]
        assert r["status"] == "failed", r
        assert name in r["error"] and reason in r["error"], r["error"]
    good = [n for n in rows if n not in BROKEN]
    for n in good:
        assert rows[n]["status"] in ("ok", "skipped"), rows[n]
        assert rows[n]["k"] == PARAMS["k"]
        assert (out / f"{n}.npz").is_file()
    with open(out / "summary.csv", newline="") as f:
        summary = {r["name"]: r for r in csv.DictReader(f)}
    assert set(summary) == set(rows)
    for n, r in rows.items():
        assert summary[n]["status"] == r["status"]
    return good


def test_local_pool_resumes_and_isolates_a_crash(tmp_path, monkeypatch):
    src = make_set(tmp_path, shared_dir(), 3)
    # A valid mesh whose worker process aborts (the test hook): retried once, then its row.
    V, F = sm.shape("sphere:res=2")
    sm.write_mesh(src / "crash.off", V, F)
    monkeypatch.setenv("SPECTRAL_MESH_BATCH_TEST_ABORT", "crash.off")
    out = tmp_path / "out"
    first = sm.batch(src, out, processes=2, **PARAMS)
    rows = by_name(first)
    assert rows["crash.off"]["status"] == "failed"
    assert "died" in rows["crash.off"]["error"], rows["crash.off"]
    monkeypatch.delenv("SPECTRAL_MESH_BATCH_TEST_ABORT")
    # Good shapes computed, broken ones failed with their reason.
    for n, r in rows.items():
        if n in BROKEN or n == "crash.off":
            assert r["status"] == "failed"
        else:
            assert r["status"] == "ok", r
    before = results(out)
    # Again: no work for the good and broken shapes; the crash (no marker) is tried again
    # and now succeeds (the hook is off).
    second = by_name(sm.batch(src, out, processes=2, **PARAMS))
    for n, r in second.items():
        if n in BROKEN:
            assert (r["status"], r["reused"]) == ("failed", True)
        elif n == "crash.off":
            assert r["status"] == "ok"
        else:
            assert r["status"] == "skipped", r
    after = results(out)
    assert {n: b for n, b in after.items() if n != "crash.off.npz"} == before
    # An edited input (a comment appended): exactly that shape computed again.
    edited = "gen1.off"
    with open(src / edited, "a") as f:
        f.write("# edited\n")
    third = by_name(sm.batch(src, out, processes=2, **PARAMS))
    changed = sorted(n for n, r in third.items() if r["status"] == "ok")
    assert changed == [edited]


def _kill_one_worker_when_started(client, out: Path, killed: list, deadline: float):
    while time.monotonic() < deadline:
        if any(out.glob("*.npz")):
            pids = client.run(os.getpid)
            pid = sorted(pids.values())[0]
            os.kill(pid, signal.SIGKILL)
            killed.append(pid)
            return
        time.sleep(0.01)


def test_dask_cluster_with_a_killed_worker_gives_the_local_results(tmp_path):
    distributed = pytest.importorskip("distributed")
    src = make_set(tmp_path, shared_dir(), 6)
    local = tmp_path / "local"
    reference = sm.batch(src, local, processes=2, **PARAMS)
    good = check_rows(reference, src, local)
    out = tmp_path / "dask"
    with distributed.LocalCluster(host="127.0.0.1", n_workers=2, threads_per_worker=1,
                                  processes=True, dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        killed: list = []
        killer = threading.Thread(target=_kill_one_worker_when_started,
                                  args=(client, out, killed, time.monotonic() + 60))
        killer.start()
        records = sm.batch(src, out, client=client, timeout=240, **PARAMS)
        killer.join()
        assert killed, "no worker was killed"
        assert check_rows(records, src, out) == good
        # A task whose worker died after it wrote its result (before the scheduler gathered
        # the record) runs again elsewhere and finds that result up to date: "skipped".
        assert all(by_name(records)[n]["status"] in ("ok", "skipped") for n in good)
        assert any(by_name(records)[n]["status"] == "ok" for n in good)
        # Bit for bit the local run's results.
        assert results(out) == results(local)
        # A second run does no work.
        again = by_name(sm.batch(src, out, client=client, timeout=120, **PARAMS))
        assert sorted(n for n, r in again.items() if r["status"] == "ok") == []
        assert all(again[n]["status"] == "skipped" for n in good)
        # Editing one input recomputes exactly that shape.
        edited = "gen2.off"
        with open(src / edited, "a") as f:
            f.write("# edited\n")
        third = by_name(sm.batch(src, out, client=client, timeout=120, **PARAMS))
        assert sorted(n for n, r in third.items() if r["status"] == "ok") == [edited]


def test_dask_resources_route_large_shapes_and_progress_reports_each(tmp_path):
    """`resources=` as a function of (path, size): the shapes that ask for a resource run
    only on the worker that has it; `progress(done, total, record)` is called once per
    shape with done counting up to total. A SpecCluster on 127.0.0.1: one plain worker
    process and one started with the resource `bigmem`."""
    distributed = pytest.importorskip("distributed")
    src = tmp_path / "set"
    src.mkdir()
    sizes = {}
    for i, res in enumerate([1, 1, 2, 1, 2]):
        V, F = sm.shape(f"torus:res={res},R={1.2 + 0.1 * i},r=0.4")
        name = f"t{i}_res{res}.off"
        sm.write_mesh(src / name, V, F)
        sizes[name] = (src / name).stat().st_size
    threshold = sorted(sizes.values())[2]  # the two res=2 files are strictly larger
    big = {n for n, s in sizes.items() if s > threshold}
    assert big == {"t2_res2.off", "t4_res2.off"}

    def ask(path, size):
        return {"bigmem": 1} if size > threshold else None

    seen = []

    def progress(done, total, record):
        seen.append((done, total, record["name"], record["status"]))

    nanny = {"host": "127.0.0.1", "nthreads": 1, "dashboard_address": None}
    workers = {
        "plain": {"cls": distributed.Nanny, "options": dict(nanny)},
        "big": {"cls": distributed.Nanny, "options": dict(nanny, resources={"bigmem": 1})},
    }
    scheduler = {"cls": distributed.Scheduler,
                 "options": {"host": "127.0.0.1", "dashboard_address": None}}
    out = tmp_path / "out"
    with distributed.SpecCluster(workers=workers, scheduler=scheduler) as cluster, \
            distributed.Client(cluster) as client:
        client.wait_for_workers(2, timeout=60)
        big_addr = [a for a, w in client.scheduler_info()["workers"].items()
                    if w.get("resources", {}).get("bigmem")]
        assert len(big_addr) == 1
        with distributed.get_task_stream(client) as ts:
            records = sm.batch(src, out, client=client, timeout=240, resources=ask,
                               progress=progress, k=10)
        ran_on = {}
        for t in ts.data:
            key = t["key"] if isinstance(t["key"], str) else str(t["key"])
            for n in sizes:
                if key.endswith(n):
                    ran_on[n] = t["worker"]
    assert all(r["status"] == "ok" for r in records), records
    assert set(ran_on) == set(sizes), ran_on
    for n in big:
        assert ran_on[n] == big_addr[0], (n, ran_on)
    assert [d for d, _, _, _ in seen] == list(range(1, len(sizes) + 1))
    assert {t for _, t, _, _ in seen} == {len(sizes)}
    assert sorted(n for _, _, n, _ in seen) == sorted(sizes)
