#!/bin/sh
# Trains the bundled model (models/default/) from orders/: the CASE 1
# demonstrations (sequence ascending) of the line2 cell, 3 and 5 products.
# Usage: scripts/train-default.sh [SEED]
set -eu
bin=${CARGO_TARGET_DIR:-target}/release/packwright
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$bin" compile orders/suites/teach.pack -o "$tmp/teach"
"$bin" train "$tmp/teach" -o models/default --seed "${1:-0}" \
  --demos teach_2of3 teach_3of3 teach_3of5 teach_4of5 teach_3of5_far
