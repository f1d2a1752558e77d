#!/usr/bin/env bash
# Fills fuzz/corpus/<target>/ with seeds: the real files from tests/data (small glTF/GLB files, IES
# files, 4 KB prefixes of the environment maps) and the small synthetic files of examples/make_seeds.rs.
# Usage: fuzz/seed.sh   (from anywhere; safe to re-run, existing corpus files are kept)
set -euo pipefail
fuzz_dir="$(cd "$(dirname "$0")" && pwd)"
data="$fuzz_dir/../tests/data"
corpus="$fuzz_dir/corpus"
mkdir -p "$corpus/gltf_import" "$corpus/ies_parse" "$corpus/env_map"

if [ -d "$data" ]; then
    # glTF: every .glb and self-contained .gltf under 200 KB (external buffers cannot be resolved in memory).
    find "$data/gltf" \( -name '*.glb' -o -name '*.gltf' \) -size -200k | while read -r f; do
        grep -q '"uri" *: *"[^d"][^"]*\.bin"' "$f" 2>/dev/null && continue # external buffer; packed below
        cp "$f" "$corpus/gltf_import/$(basename "$(dirname "$f")")_$(basename "$f")"
    done
    find "$data/ies" -name '*.ies' -exec cp {} "$corpus/ies_parse/" \;
    # Environment maps are megabytes: their headers and first chunks are enough to seed the decoders.
    find "$data/env" \( -name '*.exr' -o -name '*.hdr' \) | while read -r f; do
        head -c 4096 "$f" > "$corpus/env_map/head4k_$(basename "$f")"
    done
else
    echo "seed.sh: $data not found; synthetic seeds only" >&2
fi

cd "$fuzz_dir"
cargo run --quiet --example make_seeds -- "$corpus" "$data"
for t in gltf_import ies_parse env_map tile_exr bake_part; do
    echo "$t: $(ls "$corpus/$t" | wc -l) seed files, $(du -sh "$corpus/$t" | cut -f1)"
done
