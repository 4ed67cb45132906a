#!/bin/sh
# groombake's physical model against the C++ PositionBasedDynamics library
# (its direct solver for stiff rods and its Cosserat rods), measured in the
# same run: the cantilever droop of both (accuracy), then timed blocks of
# the library interleaved with `groombake bench` on the same groom, thread
# count by thread count, then a markdown summary (summary.py). Not run by CI
# or `cargo test`; see README.md here.
#
# Usage: bench/reference/compare.sh [GROOMBAKE]   (default: target/release/groombake)
# Environment:
#   PBD_SRC   PositionBasedDynamics checkout (commit d0894bdb0190c5f273c0500ecad0e8c2bf21fc5f)
#   GP_SRC    GenericParameters checkout (commit a4e2744eea526270cfe38b826440d09f66473316)
#   WORK      build and scratch folder (default /tmp/pbd-bench)
#   STRANDS   strands x 32 vertices (default 10000); REPEATS (default 3);
#   STEPS     steps per timed block (default 10); THREADS (default 1,2)
#   DIRECT_ITERATIONS (default 1), COSSERAT_ITERATIONS (default 5)
set -eu
here=$(cd "$(dirname "$0")" && pwd)
groombake=${1:-$here/../../target/release/groombake}
: "${PBD_SRC:?set PBD_SRC to a PositionBasedDynamics checkout}"
: "${GP_SRC:?set GP_SRC to a GenericParameters checkout}"
WORK=${WORK:-/tmp/pbd-bench}
STRANDS=${STRANDS:-10000}
REPEATS=${REPEATS:-3}
STEPS=${STEPS:-10}
THREADS=${THREADS:-1,2}
DIRECT_ITERATIONS=${DIRECT_ITERATIONS:-1}
COSSERAT_ITERATIONS=${COSSERAT_ITERATIONS:-5}
mkdir -p "$WORK/obj"

# The library's simulation sources (no GUI, no Discregrid collision
# detection), double precision as its CMake default (USE_DOUBLE_PRECISION).
flags="-O3 -march=native -fopenmp -DNDEBUG -DUSE_DOUBLE -std=c++17 -w -I$PBD_SRC -I$GP_SRC -I$GP_SRC/GenericParameters -I/usr/include/eigen3"
for f in "$PBD_SRC"/PositionBasedDynamics/*.cpp "$PBD_SRC"/Simulation/*.cpp \
    "$PBD_SRC"/Utils/IndexedFaceMesh.cpp "$PBD_SRC"/Utils/IndexedTetMesh.cpp "$PBD_SRC"/Utils/VolumeIntegration.cpp; do
    case $f in *CubicSDF*) continue ;; esac
    o="$WORK/obj/$(basename "$(dirname "$f")")_$(basename "$f" .cpp).o"
    [ "$o" -nt "$f" ] || echo "g++ $flags -c $f -o $o"
done | xargs -P 2 -I{} nice -n 10 sh -c '{}'
nice -n 10 g++ $flags "$here/pbd_driver.cpp" "$WORK"/obj/*.o -o "$WORK/pbd_driver"

# The groom `groombake bench` steps: its generated scalp, 24 cm strands of
# 31 edges.
"$groombake" generate straight --strands "$STRANDS" --length 0.24 \
    --segment-length 0.0077419355 -o "$WORK/groom.obj"

{
    echo "# cantilever droop (elastica: 5 cm 0.006998 m, 10 cm 0.06760 m)"
    for length in 0.05 0.10; do
        "$WORK/pbd_driver" droop direct $length 31 1 "$DIRECT_ITERATIONS"
        "$WORK/pbd_driver" droop cosserat $length 31 1 "$COSSERAT_ITERATIONS"
    done

    echo "# timed blocks (JSON lines; groombake's before each of the library's)"
    between="\"$groombake\" bench --strands $STRANDS --vertices 32 --threads \$PBD_THREADS --steps $STEPS --json"
    PBD_BETWEEN=$between "$WORK/pbd_driver" bench direct "$WORK/groom.obj" "$STEPS" "$THREADS" 1 "$DIRECT_ITERATIONS" "$REPEATS"
    PBD_BETWEEN=$between "$WORK/pbd_driver" bench cosserat "$WORK/groom.obj" "$STEPS" "$THREADS" 1 "$COSSERAT_ITERATIONS" "$REPEATS"
} | tee "$WORK/compare.log"
python3 "$here/summary.py" <"$WORK/compare.log"
