#!/usr/bin/env bash
# Seeds fuzz/corpus/<target>/ from real files in the repository: the
# samples, the importers' test data, tests/data, and each of those grooms
# converted by groombake into every format it writes (so every reader gets
# a well-formed file of its own format to mutate).
# Usage: fuzz/seed_corpus.sh [path/to/groombake]
set -euo pipefail
cd "$(dirname "$0")"
repo=..
groombake=${1:-$repo/target/release/groombake}
seed() { # target files...
  local target=$1; shift
  mkdir -p "corpus/$target"
  for f in "$@"; do [ -f "$f" ] && cp "$f" "corpus/$target/$(basename "$f")"; done
  return 0
}
shopt -s nullglob
data=("$repo"/tests/data/* "$repo"/tests/data/usd/* "$repo"/importers/tests/data/* "$repo"/samples/*)
converted=$(mktemp -d)
trap 'rm -rf "$converted"' EXIT
if [ -x "$groombake" ]; then
  for source in "$repo"/importers/tests/data/reference.usda "$repo"/tests/data/*.hair; do
    [ -f "$source" ] || continue
    for ext in hair data obj gltf glb usda usdc abc; do
      "$groombake" convert "$source" "$converted/converted_$(basename "${source%.*}").$ext" \
        >/dev/null 2>&1 || true
    done
  done
fi
all=("${data[@]}" "$converted"/*)
pick() { for f in "${all[@]}"; do case "$f" in *."$1") echo "$f";; esac; done; }
seed abc_reader $(pick abc)
seed gltf_reader $(pick gltf) $(pick glb)
seed usda_reader $(pick usda)
seed usdc_reader $(pick usdc) $(pick usd)
seed hair_reader $(pick hair)
seed data_reader $(pick data)
seed obj_reader $(pick obj)
seed timeline $(pick toml)
for d in corpus/*/; do echo "$(ls "$d" | wc -l) seeds in $d"; done
