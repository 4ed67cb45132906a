#!/usr/bin/env bash
# Regenerates the pictures of samples/README.md (samples/img/NAME.png), one
# per sample, with `groombake preview`: each timeline is baked in memory and
# drawn before the first stage and after each stage, with its colliders, in
# the view its [preview] names (or the one that shows its change), coloured
# as its [preview] says.
#
# Uses $GROOMBAKE if set, else builds and uses the release binary.
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${GROOMBAKE:-}"
if [ -z "$bin" ]; then
  cargo build --release --quiet
  bin="${CARGO_TARGET_DIR:-target}/release/groombake"
fi
mkdir -p samples/img
for timeline in samples/*.toml; do
  name=$(basename "$timeline" .toml)
  start=$(date +%s)
  "$bin" preview "$timeline" -o "samples/img/$name.png" --panel-size 320x320
  echo "samples/img/$name.png ($(( $(date +%s) - start )) s)"
done
