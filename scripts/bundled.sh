#!/usr/bin/env bash
# Measure one model (the bundled one by default) on generated cells it was
# not taught: for each seed, generate the cell (`packwright generate`),
# run `packwright eval` on its six suites with the model, and print the
# totals over all the cells: scenarios, packed, reasoner right, packed
# without fallback, and the fallbacks by kind.
#
# The seeds the README reports the bundled model on (fixed before they
# were first measured; never tuned on): 1000-1019 (reporting, --limit 50)
# and 3000-3099 (probe, --limit 5). Develop on others (2000-2019 and up).
#
# Usage: scripts/bundled.sh SEED...
# Environment:
#   PACKWRIGHT  the binary (default: target/release/packwright)
#   MODEL       the model directory (default: models/default)
#   LIMIT       scenarios per suite (default: 50)
#   FAMILY      standard (default), wide or compact (`generate --help`)
#   EVAL_ARGS   more arguments for `packwright eval` (e.g. --baselines)
#   WORK        where the files go (default: a new directory under /tmp);
#               per seed: PREFIX_SEED.pack and PREFIX_SEED.eval.json

set -euo pipefail

cd "$(dirname "$0")/.."
bin=${PACKWRIGHT:-${CARGO_TARGET_DIR:-target}/release/packwright}
if [ ! -x "$bin" ]; then
  echo "bundled.sh: no binary at $bin (cargo build --release, or set PACKWRIGHT)" >&2
  exit 2
fi
if [ $# -eq 0 ]; then
  echo "usage: scripts/bundled.sh SEED... (the README reports 1000-1019 and 3000-3099)" >&2
  exit 2
fi
if ! command -v jq >/dev/null; then
  echo "bundled.sh: needs jq for its totals" >&2
  exit 2
fi
model=${MODEL:-models/default}
limit=${LIMIT:-50}
read -ra eval_args <<<"${EVAL_ARGS:-}"
work=${WORK:-$(mktemp -d "${TMPDIR:-/tmp}/packwright-bundled.XXXXXX")}
mkdir -p "$work"

reports=()
for seed in "$@"; do
  # `generate` prints the file it wrote (and refuses a FAMILY it has not).
  pack=$("$bin" generate --family "${FAMILY:-standard}" --seed "$seed" -o "$work")
  echo "== $(basename "$pack" .pack)" >&2
  report=${pack%.pack}.eval.json
  "$bin" eval "$pack" --model "$model" --limit "$limit" --quiet \
    ${eval_args[@]+"${eval_args[@]}"} --json >"$report"
  reports+=("$report")
done

echo "files in $work"
# One line per planner: the counts summed over every suite of every cell.
cat "${reports[@]}" | jq -rs '
  [.[].rows[]] | group_by(.planner)[] |
  {
    planner: .[0].planner,
    scenarios: (map(.scenarios) | add),
    packed: (map(.sr.rate * .scenarios | round) | add),
    reasoner: (map(select(.reasoner_sr != null) | .reasoner_sr.rate * .reasoner_scenarios | round) | add),
    # The baselines have no fallback (their rate is null): all they packed.
    no_fallback: (map((.sr_no_fallback // .sr).rate * .scenarios | round) | add),
    violations: (map(.violations) | add),
    fallbacks: (map(.fallback_kinds | to_entries[]) | group_by(.key)
      | map({key: .[0].key, value: (map(.value) | add)}) | from_entries)
  } |
  "\(.planner): \(.packed) of \(.scenarios) packed, reasoner right on \(.reasoner // "n/a (no reasoner)"), \(.no_fallback) without fallback, \(.violations) violations; fallbacks: \(.fallbacks | if . == {} then "none" else (to_entries | map("\(.value) \(.key)") | join(", ")) end)"
'
