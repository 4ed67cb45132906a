#!/usr/bin/env bash
# The "no silent change" round-trip table (issue 36): every source below x
# every format groombake writes, `convert SRC OUT` (not strict), then each
# conversion is
#   warned  convert printed a warning (what it could not keep),
#   clean   no warning, and `groombake diff SRC OUT` equal within 1e-6 m,
#   silent  no warning, but diff finds a difference (must stay 0),
#   other   convert refused, or diff could not read OUT (listed).
# usage: tests/round_trip_table.sh path/to/groombake
set -u
bin=${1:?usage: $0 path/to/groombake}
data="$(cd "$(dirname "$0")" && pwd)/data/usd"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
sources=("$data"/openusd/*.usda)
for name in color3f constant_widths inherits instancing legacy_pointfloat mixed_types \
  pinned_wrap reference_internal; do
  sources+=("$data/$name.usda")
done
clean=0 warned=0 silent=0 other=0
for source in "${sources[@]}"; do
  for format in usda usdc abc glb gltf obj hair data; do
    out="$work/out.$format"
    rm -f "$out"
    if ! said=$("$bin" convert "$source" "$out" 2>&1 >/dev/null); then
      echo "other   $(basename "$source") -> $format: $said" | cut -c1-240
      other=$((other + 1))
      continue
    fi
    if grep -q warning <<<"$said"; then
      warned=$((warned + 1))
      continue
    fi
    "$bin" diff "$source" "$out" --tolerance 1e-6 >"$work/diff.txt" 2>&1
    case $? in
      0) clean=$((clean + 1)) ;;
      1) silent=$((silent + 1))
         echo "silent  $(basename "$source") -> $format: $(head -3 "$work/diff.txt" | tr '\n' ' ')" | cut -c1-240 ;;
      *) other=$((other + 1))
         echo "other   $(basename "$source") -> $format: $(head -2 "$work/diff.txt" | tr '\n' ' ')" | cut -c1-240 ;;
    esac
  done
done
echo "${#sources[@]} sources x 8 formats: clean $clean, warned $warned, silent $silent, other $other"
[ "$silent" -eq 0 ]
