#!/usr/bin/env bash
# Per-vertex field files written by spectral_mesh::io::write_field read back in
# numpy.loadtxt as the same float64 values, bit for bit (2000 values: extremes,
# subnormals, -0.0 and a spread of bit patterns). Arguments: CLI PYTHON.
set -euo pipefail
py="$2"
SPECTRAL_MESH_PYTHON="$py" cargo test --release --quiet --workspace --test io_roundtrip_props \
  field_text_reads_back_in_numpy -- --nocapture
