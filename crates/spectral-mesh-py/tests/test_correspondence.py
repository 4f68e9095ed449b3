"""Shape correspondence from Python: ZoomOut in both directions on a shuffled copy (the
maps are the known permutation and its inverse, and agree with each other)."""

from __future__ import annotations

import numpy as np
import pytest

import spectral_mesh as sm


def blob(res: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """An icosphere deformed without any symmetry."""
    V, F = sm.shape(f"sphere:res={res}")
    x, y, z = V[:, 0], V[:, 1], V[:, 2]
    W = np.column_stack([
        1.6 * x + 0.35 * x * x + 0.2 * y,
        0.9 * y + 0.25 * z * z,
        0.7 * z + 0.3 * x * y + 0.15 * z ** 3,
    ])
    return W, F


def shuffled(V: np.ndarray, F: np.ndarray, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The mesh with its vertices renumbered: vertex ``i`` of the copy is vertex
    ``perm[i]`` of the original (``perm`` is the true ``p2p_21``)."""
    perm = np.random.default_rng(seed).permutation(len(V))
    inv = np.empty_like(perm)
    inv[perm] = np.arange(len(V))
    return V[perm], inv[F], perm


def test_zoomout_both_directions_on_a_shuffled_pair():
    V1, F1 = blob()
    V2, F2, perm = shuffled(V1, F1, 3)
    inv = np.empty_like(perm)
    inv[perm] = np.arange(len(perm))
    C = sm.functional_map(V1, F1, V2, F2, k=20)
    assert C.shape == (20, 20)
    both = sm.zoomout(V1, F1, V2, F2, C, 50, direction="both")
    assert len(both) == 4
    C21, p21, C12, p12 = both
    assert C21.shape == C12.shape == (50, 50)
    assert p21.shape == (len(V2),) and p12.shape == (len(V1),)
    assert np.mean(p21 == perm) > 0.99
    assert np.mean(p12 == inv) > 0.99
    # Consistent: inverse point maps, transposed functional maps.
    assert np.mean(p21[p12] == np.arange(len(V1))) > 0.99
    assert np.linalg.norm(C12 - C21.T) < 0.05 * np.linalg.norm(C21)
    # One direction at a time gives the same as both.
    fwd = sm.zoomout(V1, F1, V2, F2, C, 50, direction="forward")
    rev = sm.zoomout(V1, F1, V2, F2, C, 50, direction="reverse")
    assert len(fwd) == len(rev) == 2
    np.testing.assert_array_equal(fwd[1], p21)
    np.testing.assert_array_equal(rev[1], p12)
    np.testing.assert_array_equal(rev[0], C12)
    # The default is the library's (forward).
    assert sm.zoomout(V1, F1, V2, F2, C, 30)[1].shape == (len(V2),)
    with pytest.raises(ValueError, match="forward, reverse or both"):
        sm.zoomout(V1, F1, V2, F2, C, 30, direction="sideways")


def _pair_set(tmp_path):
    """A blob, a shuffled copy with its true map, and a broken file."""
    src = tmp_path / "in"
    src.mkdir()
    V1, F1 = blob()
    V2, F2, perm = shuffled(V1, F1, 5)
    sm.write_mesh(src / "blob.off", V1, F1)
    sm.write_mesh(src / "copy.off", V2, F2)
    (src / "broken.off").write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n")
    truth = src / "truth.txt"
    truth.write_text("".join(f"{v}\n" for v in perm))
    pairs = [("copy.off", "blob.off", truth), ("broken.off", "blob.off")]
    return src, pairs, perm


PAIR_PARAMS = dict(k=20, zoomout_k=40, direction="both")


def _check_pairs(records, out, perm):
    import csv

    assert [r["name"] for r in records] == ["copy.off--blob.off", "broken.off--blob.off"]
    ok, bad = records
    assert ok["status"] == "ok", ok["error"]
    assert ok["n_source"] == ok["n_target"] == len(perm)
    assert ok["k_final"] == 40 and ok["direction"] == "both"
    assert ok["mean_geodesic_error"] < 0.01 and ok["exact_share"] > 0.99
    assert ok["outputs"] == ["maps/copy.off--blob.off.txt", "maps/copy.off--blob.off.reverse.txt"]
    mapped = np.loadtxt(out / "maps" / "copy.off--blob.off.txt", dtype=np.int64)
    assert np.mean(mapped == perm) > 0.99
    back = np.loadtxt(out / "maps" / "copy.off--blob.off.reverse.txt", dtype=np.int64)
    assert np.mean(mapped[back] == np.arange(len(perm))) > 0.99
    assert bad["status"] == "failed" and "broken.off" in bad["error"]
    with open(out / "pairs.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [r["name"] for r in rows] == [r["name"] for r in records]
    assert float(rows[0]["mean_geodesic_error"]) == ok["mean_geodesic_error"]
    assert rows[1]["status"] == "failed" and "broken.off" in rows[1]["error"]


def test_match_pairs_locally(tmp_path):
    src, pairs, perm = _pair_set(tmp_path)
    out = tmp_path / "out"
    seen = []
    records = sm.match_pairs(src, out, pairs=pairs, progress=lambda d, n, r: seen.append((d, n)),
                             **PAIR_PARAMS)
    _check_pairs(records, out, perm)
    assert seen == [(1, 2), (2, 2)]
    # Pairings by rule: three inputs give three pairs ("all") or two ("consecutive").
    names = [r["name"] for r in sm.match_pairs(src, tmp_path / "c", pairs="consecutive",
                                               k=10, zoomout_k=0)]
    assert names == ["blob.off--broken.off", "broken.off--copy.off"]
    with pytest.raises(ValueError, match="names none"):
        sm.match_pairs(src, tmp_path / "d", pairs=[("nothere.off", 0)])
    with pytest.raises(ValueError, match="'all', 'consecutive'"):
        sm.match_pairs(src, tmp_path / "d", pairs="every")


def test_match_pairs_on_a_local_dask_cluster(tmp_path):
    distributed = pytest.importorskip("distributed")
    src, pairs, perm = _pair_set(tmp_path)
    out = tmp_path / "out"
    # One in-process worker, over TCP on the loopback interface only.
    with distributed.LocalCluster(host="127.0.0.1", protocol="tcp://", n_workers=1,
                                  threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        records = sm.match_pairs(src, out, pairs=pairs, client=client, timeout=240,
                                 **PAIR_PARAMS)
    _check_pairs(records, out, perm)
