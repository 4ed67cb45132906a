#!/usr/bin/env bash
# Regenerates docs/img/bake_report_html.png: the HTML bake report of
# samples/bed_hair.toml as the README's quick start writes it
# (`--report out/report.html`), photographed by headless Chromium
# (Debian package `chromium`) at 1200 px wide.
#
# Uses $GROOMBAKE if set, else builds and uses the release binary.
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${GROOMBAKE:-}"
if [ -z "$bin" ]; then
  cargo build --release --quiet
  bin="${CARGO_TARGET_DIR:-target}/release/groombake"
fi
bin=$(realpath "$bin")
browser=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$browser" ]; then
  echo "make_report_picture.sh: no chromium on PATH (apt-get install chromium)" >&2
  exit 2
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Bake in a copy, so the page shows the paths a user sees (./out/...).
cp -r samples "$work/samples"
(cd "$work" && "$bin" bake samples/bed_hair.toml --report out/report.html -q 2>/dev/null)
mkdir -p docs/img
"$browser" --headless --no-sandbox --disable-gpu --hide-scrollbars \
  --window-size=1200,2020 --screenshot="$work/shot.png" \
  "file://$work/out/report.html" >/dev/null 2>&1
mv "$work/shot.png" docs/img/bake_report_html.png
echo "wrote docs/img/bake_report_html.png"
