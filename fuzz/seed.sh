#!/usr/bin/env bash
# Fills fuzz/corpus/<target>/ with seeds: the real files from tests/data (small glTF/GLB files, IES
# files, 4 KB prefixes of the environment maps), the README's manifests with a few more naming real files of
# tests/data, and the small synthetic files of examples/make_seeds.rs. Writes the manifest target's dictionary,
# fuzz/dict/manifest.dict, from the property names and values of docs/manifest.schema.json.
# Usage: fuzz/seed.sh   (from anywhere; safe to re-run, existing corpus files are kept)
set -euo pipefail
fuzz_dir="$(cd "$(dirname "$0")" && pwd)"
data="$fuzz_dir/../tests/data"
corpus="$fuzz_dir/corpus"
mkdir -p "$corpus/gltf_import" "$corpus/ies_parse" "$corpus/env_map" "$corpus/manifest"

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

# Manifests: the README's examples, and jobs naming real files (the target plans them from tests/data).
awk '/^```json/{block=""; inside=1; next} /^```/{if (inside && block ~ /"jobs"/) print block > sprintf("%s/readme_%d.json", dir, ++n); inside=0; next} inside{block=block $0 "\n"}' \
    dir="$corpus/manifest" "$fuzz_dir/../README.md"
while IFS= read -r line; do
    echo "$line" > "$corpus/manifest/job_$(echo "$line" | cksum | cut -d' ' -f1).json"
done <<'EOF'
{"version": 1, "jobs": [{"scene": "gltf/bevy/CornellBox.glb", "output": "out/box.exr", "size": "16x8", "spp": 4}]}
{"jobs": [{"scene": "gltf/bevy/CornellBox.glb", "output": "o/f_##.exr", "frames": "1-9x2", "chunk": 2, "fps": 30}]}
{"jobs": [{"output": "a.png", "frames": "0..3,7", "settings": {"integrator": "direct", "restir": true}}]}
{"jobs": [{"output": "a.exr", "settings": {"env": "env/spiaggia_di_mondello_1k.hdr", "env_intensity": 2}}]}
{"jobs": [{"output": "a.exr", "settings": {"sky": [0.3, 1, 0.2], "max_depth": 3, "pattern": "independent"}}]}
{"jobs": [{"output": "a.exr"}, {"output": "./a.exr", "camera": {"environment_at": [0, 1, 0]}}]}
{"jobs": [{"bake": "lightmaps", "scene": "gltf/bevy/CornellBox.glb", "output": "maps", "parts": 3, "settings": {"size": 8, "spp": 2}}]}
{"jobs": [{"bake": "volume", "scene": "gltf/bevy/CornellBox.glb", "output": "v.ktx2", "settings": {"resolution": [2, 2, 2]}}]}
EOF
# The dictionary: every property name and enumerated value of the schema, quoted as in JSON.
grep -o '"[a-z_$][a-z_0-9]*"' "$fuzz_dir/../docs/manifest.schema.json" | sort -u | sed 's/"/\\"/g; s/.*/"&"/' \
    > "$fuzz_dir/dict/manifest.dict"

cd "$fuzz_dir"
cargo run --quiet --example make_seeds -- "$corpus" "$data"
for t in gltf_import ies_parse env_map tile_exr bake_part manifest; do
    # (du may race a running fuzzer that replaces corpus files.)
    echo "$t: $(ls "$corpus/$t" | wc -l) seed files, $(du -sh "$corpus/$t" 2>/dev/null | cut -f1)"
done
