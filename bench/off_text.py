"""Reading a plain OFF triangle mesh into NumPy arrays, for the peers' side of the benches
(numpy only, so that it adds nothing to the peer's import time)."""
import numpy as np


def read_off(path):
    """`(V, F)` of a plain OFF file of triangles: V float64 (n x 3), F int64 (m x 3)."""
    with open(path) as f:
        head = f.readline().split()
        assert head[0] == "OFF"
        line = f.readline()
        while line.startswith("#") or not line.strip():
            line = f.readline()
        nv, nf = (int(x) for x in line.split()[:2])
        rest = np.array(f.read().split(), dtype=np.float64)
    V = rest[: 3 * nv].reshape(nv, 3)
    F = rest[3 * nv : 3 * nv + 4 * nf].reshape(nf, 4)[:, 1:].astype(np.int64)
    return V, F
