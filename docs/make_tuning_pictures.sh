#!/usr/bin/env bash
# Regenerates the pictures of docs/tuning.md (docs/img/tune_*.png): for each
# parameter a TD turns, three small bakes of one scene with the parameter
# too low, about right and too high. Each bake exports its animation at 10
# frames a second and each picture is `groombake preview --frames` of a few
# of those frames side by side (frame N is at N/10 s), so the start and the
# result share one camera and one scale.
#
# Every bake is small (tens of strands, a few seconds of simulated time)
# and takes seconds with a release binary. The scenes use the default
# (physical) model.
#
# Uses $GROOMBAKE if set, else builds and uses the release binary.
# Usage: docs/make_tuning_pictures.sh [PREFIX...]
# (with prefixes, only the pictures whose name starts with one: `damping`)
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${GROOMBAKE:-}"
if [ -z "$bin" ]; then
  cargo build --release --quiet
  bin="${CARGO_TARGET_DIR:-target}/release/groombake"
fi
bin=$(realpath "$bin")
only=("$@")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p docs/img

# shot NAME VIEW FRAMES: bakes the timeline on stdin (plus an animated
# export at 10 fps) and draws FRAMES (comma-separated) of it from VIEW into
# docs/img/tune_NAME.png.
shot() {
  local name=$1 view=$2 frames=$3 start
  if [ ${#only[@]} -gt 0 ] && ! printf '%s\n' "${only[@]}" | grep -q -x -F -e "${name%%_*}" -e "$name"; then
    cat > /dev/null
    return
  fi
  start=$(date +%s)
  {
    cat
    printf '[[export]]\npath = "anim.glb"\nwhat = "animated"\nfps = 10\n'
  } > "$work/$name.toml"
  "$bin" bake "$work/$name.toml" --out "$work/$name" -q
  "$bin" preview "$work/$name/anim.glb" --frames "$frames" --view "$view" \
    --panel-size 150x150 -o "docs/img/tune_$name.png"
  echo "docs/img/tune_$name.png ($(( $(date +%s) - start )) s)"
}

# A scalp of 60 strands of 12 cm (1 cm edges), combed straight out, that
# falls under gravity for `duration` seconds: without the sag-free start
# (which would make the groom the shape that stands still), so the
# stiffness and damping rows show hair that moves.
scalp() { # youngs_modulus damping duration
  cat <<EOF
[groom]
generate = { layout = "scalp", strands = 60, length = 0.12, segment_length = 0.01 }
[material]
youngs_modulus = $1
[solver]
sag_free = false
damping = { linear = $2, angular = $2 }
[[stage]]
kind = "settle"
duration = $3
EOF
}

# A swatch of 30 strands, 4 cm wide, hanging from y = 0.3 m.
swatch() { # hydrogen share, length (m), segment_length (m)
  cat <<EOF
seed = 1
[groom]
generate = { layout = "swatch", strands = 30, length = $2, segment_length = $3, swatch_width = 0.04, head_center = [0.0, 0.30, 0.0] }
[material]
bonds = { hydrogen = $1, ionic = 0.28, disulfide = 0.20, peptide = 0.17 }
EOF
}

# A blow-dry set: a swatch of 6 cm hair (short hair shows a set best:
# gravity bends it least) is wetted (0.2 s), dried for 1.5 s while a
# blower holds it sideways (the blower itself re-forms no bonds here:
# hydrogen_rate 0), then hangs for 1 s with the blower off. Frames: the
# start, the end of drying (1.7 s), the end (2.7 s).
blow_set() { # hydrogen share, drying_time
  swatch "$1" 0.06 0.005
  cat <<EOF
[[stage]]
kind = "wet"
duration = 0.2
[[stage]]
kind = "dry"
duration = 1.5
drying_time = $2
blower = { from = [-0.3, 0.25, 0.0], to = [0.0, 0.25, 0.0], strength = 200.0, hydrogen_rate = 0.0 }
[[stage]]
kind = "settle"
duration = 1.0
EOF
}

# A blower across a wet swatch of 10 cm hair for 1.2 s. Frames: the
# start, 0.6 s, 1.2 s.
blower() { # strength falloff_length from to
  swatch 0.35 0.10 0.01
  cat <<EOF
[[stage]]
kind = "wet"
duration = 0.2
[[stage]]
kind = "dry"
duration = 1.0
blower = { from = $3, to = $4, strength = $1, falloff_length = $2 }
EOF
}

# Stiffness, [material] youngs_modulus (Pa): the scalp at the start and
# after 1.5 s, from the side.
for e in 3.5e8 3.5e9 1e10; do
  scalp "$e" 2 1.5 | shot "stiffness_$e" side 0,15
done

# Damping, [solver] damping (1/s): the scalp at 0.1, 0.3, 0.6 and 1.0 s.
for c in 0 2 100; do
  scalp 3.5e9 "$c" 1.0 | shot "damping_$c" side 1,3,6,10
done

# Bond shares, [material] bonds.hydrogen: the blow-dry set.
for h in 0.1 0.35 0.7; do
  blow_set "$h" 1.0 | shot "hydrogen_$h" front 0,17,27
done

# Drying time, the dry stage's drying_time (s): the blow-dry set.
for t in 0.02 1.0 5.0; do
  blow_set 0.35 "$t" | shot "drying_time_$t" front 0,17,27
done

# Blower strength (m/s^2): the blower's axis runs through the swatch.
for a in 5 40 400; do
  blower "$a" 1.0 "[-0.3, 0.25, 0.0]" "[0.0, 0.25, 0.0]" | shot "blower_strength_$a" front 0,6,12
done

# Blower falloff_length (m): strength 200 m/s^2, the axis 30 cm in front of
# the swatch (the hair is 0.3 m off it).
for f in 0.05 0.3 3.0; do
  blower 200 "$f" "[-0.3, 0.25, 0.3]" "[0.3, 0.25, 0.3]" | shot "blower_falloff_$f" front 0,6,12
done

# Hair-hair, [solver] hair_hair.strength (m/s^2): 40 strands in a 3 cm
# swatch, hair_radius 2 mm (strands repel within 4 mm), 1 s under gravity,
# seen from the side (the swatch's plane seen edge-on).
for s in 0 2 10; do
  {
    echo "seed = 1"
    echo "[groom]"
    echo 'generate = { layout = "swatch", strands = 40, length = 0.12, segment_length = 0.01, swatch_width = 0.03, head_center = [0.0, 0.30, 0.0] }'
    echo "[solver]"
    echo "hair_radius = 0.002"
    echo "hair_hair = { strength = $s }"
    echo "[[stage]]"
    echo 'kind = "settle"'
    echo "duration = 1.0"
  } | shot "hair_hair_$s" side 0,10
done
