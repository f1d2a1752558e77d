#!/bin/sh
# Equal-time efficiency of RIS and ReSTIR reuse against the light BVH (docs/performance.md,
# "Resampled light selection"). Optional argument: images of 16 x 16 points per scene (default 2).
set -e
cd "$(dirname "$0")/.."
cargo run --release --example resampling_efficiency -- "$@"
