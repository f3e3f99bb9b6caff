#!/usr/bin/env bash
# Regenerates the pictures under docs/ that the README shows: the example
# cell line2 with order deli_crate (orders/customers/hampton_deli.pack),
# the scenario deli_mixed, the expert's executed tool path of deli_crate,
# and the charts of an evaluation run (the bundled model and the
# baselines on orders/suites/measure.pack, LIMIT scenarios per suite: all
# 100 by default, about 7 minutes on 2 cores; LIMIT=5 for a quick look).
# Every picture is deterministic but the charts' timings, which are
# measured on this machine.
#
# Usage: scripts/charts.sh
# Environment:
#   PACKWRIGHT  the binary (default: target/release/packwright)
#   LIMIT       scenarios per suite of the evaluation (default: 100)
#   DOCS        where the pictures go (default: docs)

set -euo pipefail
cd "$(dirname "$0")/.."
bin=${PACKWRIGHT:-${CARGO_TARGET_DIR:-target}/release/packwright}
if [ ! -x "$bin" ]; then
  echo "charts.sh: no binary at $bin (cargo build --release, or set PACKWRIGHT)" >&2
  exit 2
fi
limit=${LIMIT:-100}
docs=${DOCS:-docs}
mkdir -p "$docs/eval"

"$bin" draw orders/customers/hampton_deli.pack --order deli_crate -o "$docs/cell_line2_deli_crate.svg"
"$bin" draw orders/customers/hampton_deli.pack --scenario deli_mixed -o "$docs/scenario_deli_mixed.svg"
"$bin" draw orders/cells/twin_row.pack --inventory desk6 -o "$docs/cell_twin_row.svg"
if "$bin" execute --help | grep -q -- '--svg'; then
  "$bin" execute orders/customers/hampton_deli.pack --order deli_crate --planner expert \
    --svg "$docs/path_deli_crate_expert.svg" >/dev/null
fi
"$bin" eval orders/suites/measure.pack --baselines --limit "$limit" --quiet \
  --markdown "$docs/eval/table.md" --plots "$docs/eval" >/dev/null
echo "charts.sh: pictures in $docs/ (evaluation: $limit scenarios per suite)" >&2
