#!/bin/sh
# Equal-time efficiency of RIS and ReSTIR reuse against the light BVH (docs/performance.md,
# "Resampled light selection"). Optional argument: rows of the 32-point-wide image (default 16).
set -e
cd "$(dirname "$0")/.."
cargo run --release --example resampling_efficiency -- "$@"
