#!/bin/sh
# The README's scaling table of the physical model: `groombake bench` on the
# generated scalp groom at 1,000, 10,000 and 100,000 strands x 32 vertices,
# 1 and 2 threads, free hair (no hair-hair, no collider), dt 1/360, the
# model's default iterations and Newton tolerance. Prints a markdown table:
# wall and CPU time per vertex-step (the minimum of REPEATS runs), peak
# resident memory (MiB) after the timed steps (bench's `peak_memory_bytes`,
# read before its second, phase-clocked run), and the load average during
# the runs. Not run by CI.
#
# Usage: bench/scaling.sh [GROOMBAKE]   (default: target/release/groombake;
# build it with `cargo build --release` first)
# Environment: REPEATS (default 3), STRANDS (default "1000 10000 100000"),
# THREADS (default "1 2"), EXTRA (more `bench` options, e.g. "--iterations 1").
set -eu
here=$(cd "$(dirname "$0")" && pwd)
groombake=${1:-$here/../target/release/groombake}
REPEATS=${REPEATS:-3}
STRANDS=${STRANDS:-1000 10000 100000}
THREADS=${THREADS:-1 2}
EXTRA=${EXTRA:-}
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT

echo "| strands | threads | ns per vertex-step (wall) | CPU ns per vertex-step | peak memory | load average |"
echo "|---|---|---|---|---|---|"
for strands in $STRANDS; do
    # Enough timed steps for a steady figure, fewer for the large groom.
    steps=20
    [ "$strands" -ge 100000 ] && steps=3
    for threads in $THREADS; do
        : >"$scratch/runs"
        run=0
        while [ $run -lt "$REPEATS" ]; do
            # shellcheck disable=SC2086
            "$groombake" bench --strands "$strands" --vertices 32 \
                --threads "$threads" --steps "$steps" --json $EXTRA >"$scratch/out"
            # One line per run: wall ns, CPU ns, load average, peak bytes.
            for key in ns_per_vertex_step cpu_ns_per_vertex_step load_average peak_memory_bytes; do
                sed "s/.*\"$key\":\([0-9.]*\).*/\1/" "$scratch/out" | tr '\n' ' '
            done >>"$scratch/runs"
            echo >>"$scratch/runs"
            run=$((run + 1))
        done
        set -- $(awk 'NR == 1 { w = $1; c = $2; lo = $3; hi = $3; m = $4 }
            { if ($1 < w) w = $1; if ($2 < c) c = $2; if ($3 < lo) lo = $3; if ($3 > hi) hi = $3; if ($4 > m) m = $4 }
            END { print w, c, lo "-" hi, m }' "$scratch/runs")
        printf "| %s | %s | %.1f | %.1f | %d MB | %s |\n" "$strands" "$threads" "$1" "$2" $(($4 / 1048576)) "$3"
    done
done
# The figures hold for this CPU only (bench names it).
echo
sed -n 's/.*"cpu":"\([^"]*\)".*/CPU: \1/p' "$scratch/out"
