#!/usr/bin/env python3
"""The pyFM script a user would write from its README quickstart (pyfmaps 1.3): both
meshes loaded area-normalized and centred, WKS descriptors (every 2nd of 100), a 30 x 30
functional map with the quickstart's weights, ZoomOut to 100 in steps of 5, the point map
of the refined map (for each vertex of mesh 2, a vertex of mesh 1).

Usage: match_pyfm.py MESH1 MESH2 OUT.txt
"""
import sys

import numpy as np
from pyFM.functional import FunctionalMapping
from pyFM.mesh import TriMesh

mesh1 = TriMesh.load(sys.argv[1], area_normalize=True, center=True)
mesh2 = TriMesh.load(sys.argv[2], area_normalize=True, center=True)
model = FunctionalMapping(mesh1, mesh2)
model.preprocess(descr_type="WKS", subsample_step=2)
model.fit(K=30, w_descr=1e0, w_lap=1e-1, w_dcomm=1e0, w_orient=1e0)
FM_zo = model.zoomout_refine(nit=14, step=5)
p2p_21 = model.get_p2p(FM_zo)
np.savetxt(sys.argv[3], p2p_21, fmt="%d")
