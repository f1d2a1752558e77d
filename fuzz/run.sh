#!/usr/bin/env bash
# Runs every fuzz target (or those named) for SECONDS of CPU time each, one after another, seeding the corpora
# first, and prints each run's executions, coverage (libFuzzer's final stats) and CPU seconds for the README's
# table. CPU time, not wall time: on a machine shared with builds a fuzzer gets less than the clock says, so a
# watcher reads the fuzzer's CPU time from /proc and interrupts it (SIGINT: libFuzzer stops and prints its stats)
# once it has had SECONDS. A target's dictionary, fuzz/dict/TARGET.dict, is passed when it exists.
# Usage: fuzz/run.sh SECONDS [TARGET...]     (needs `cargo install cargo-fuzz`; stable Rust with RUSTC_BOOTSTRAP=1)
set -euo pipefail
seconds="${1:?usage: fuzz/run.sh SECONDS [TARGET...]}"
shift
fuzz_dir="$(cd "$(dirname "$0")" && pwd)"
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(gltf_import ies_parse env_map tile_exr bake_part manifest)
"$fuzz_dir/seed.sh" > /dev/null
cd "$fuzz_dir"
for t in "${targets[@]}"; do
    log="$fuzz_dir/artifacts/$t.log"
    mkdir -p "$fuzz_dir/artifacts"
    start=$(date +%s)
    status=0
    dict=()
    [ -f "$fuzz_dir/dict/$t.dict" ] && dict=(-dict="$fuzz_dir/dict/$t.dict")
    # Built first, so that the CPU time below is the fuzzing's alone.
    RUSTC_BOOTSTRAP=1 cargo fuzz build "$t" > "$log" 2>&1
    # The wall-time cap only guards against a fuzzer that gets no CPU at all.
    RUSTC_BOOTSTRAP=1 cargo fuzz run "$t" -- -max_total_time=$((seconds * 50)) -rss_limit_mb=4096 \
        -print_final_stats=1 "${dict[@]}" >> "$log" 2>&1 &
    runner=$!
    cpu=0 stopped=""
    while kill -0 "$runner" 2>/dev/null; do
        sleep 2
        # Once stopped, the CPU seconds at the stop are the run's (a later match may be another process).
        [ -n "$stopped" ] && continue
        fuzzer=$(pgrep -f "release/$t -" | head -1 || true)
        [ -n "$fuzzer" ] && [ -r "/proc/$fuzzer/stat" ] || continue
        # utime and stime, fields 14 and 15 of /proc/PID/stat (the name, field 2, has no spaces here).
        cpu=$(awk -v hz="$(getconf CLK_TCK)" '{printf "%.0f", ($14 + $15) / hz}' "/proc/$fuzzer/stat" 2>/dev/null || echo "$cpu")
        if [ "$cpu" -ge "$seconds" ] && [ -z "$stopped" ]; then
            kill -INT "$fuzzer" 2>/dev/null && stopped=" (stopped at the budget)"
        fi
    done
    wait "$runner" || status=$?
    runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
    edges=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*' || echo "?")
    crashes=$(ls "$fuzz_dir/artifacts/$t" 2>/dev/null | grep -c '^crash-' || true)
    echo "$t: $(( $(date +%s) - start )) s, $cpu CPU s, $runs executions, $edges edges, exit $status$stopped, $crashes crash files (log $log)"
done
