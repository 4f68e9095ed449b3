#!/usr/bin/env bash
# Regenerates the pictures the README shows (docs/*.png) with the release CLI.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
cargo build --release --quiet -p spectral-mesh-cli
cli="$root/target/release/spectral-mesh"
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
mkdir -p docs
"$cli" experiment harmonic 3torus --out "$work/h" --size 640 > /dev/null
cp "$work/h/harmonic-map-1.png" docs/harmonic-map-3torus.png
"$cli" experiment spectral-distance 3torus --distance biharmonic -k 100 --out "$work/d" --size 640 > /dev/null
cp "$work/d/filtered-spectral-distance.png" docs/biharmonic-distance-3torus.png
"$cli" experiment diffusion-basis irregular-sphere:res=4 --t 0.01 -k 100 --out "$work/b" --size 640 --view front > /dev/null
cp "$work/b/diffusion-basis.png" docs/heat-basis-irregular-sphere.png
echo "wrote docs/harmonic-map-3torus.png docs/biharmonic-distance-3torus.png docs/heat-basis-irregular-sphere.png"
