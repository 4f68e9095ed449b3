#!/usr/bin/env bash
# Functional maps and ZoomOut against pyFM (PyPI pyfmaps) on pairs made from the shared
# meshes (shuffled copies, a subdivision) and a bent shape: our energy <= pyFM's at its
# solution, our mean geodesic error after ZoomOut within 5% of pyFM's, shuffled pairs
# below 1% of sqrt(area). Arguments: CLI PYTHON.
set -euo pipefail
source "$(dirname "$0")/common.sh"
"$py" "$root/conformance/match_pyfm.py" --cli "$cli" --min-pairs 4 \
  "$meshes/cow.off" "$meshes/homer.off" "$meshes/elephant.off"
