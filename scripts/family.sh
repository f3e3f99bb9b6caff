#!/usr/bin/env bash
# Learn and measure on a family of random cells (`packwright generate`):
# for each seed, generate gen_SEED.pack (wide_SEED.pack with FAMILY=wide,
# compact_SEED.pack with FAMILY=compact),
# compile it, train a model on its sparse demonstrations and evaluate its
# six suites (CASE 1 with n, n+1 and n+2 products, CASE 2, missing stock,
# untaught slots) with the baselines, then print one row per suite and
# planner.
#
# Develop on many random seeds; report on the fixed ones below.
#
# Usage: scripts/family.sh [SEED...]          (default: $SEEDS)
# Environment:
#   PACKWRIGHT  the binary (default: target/release/packwright)
#   WORK        where the files go (default: a new directory under /tmp);
#               per seed: gen_SEED.pack, gen_SEED.out/, gen_SEED.model/,
#               gen_SEED.eval.json (wide_SEED... or compact_SEED... with
#               FAMILY=wide or compact)
#   TRAIN_ARGS  extra arguments for `packwright train` (e.g. "--epochs 50")
#   EVAL_ARGS   arguments for `packwright eval` (default: --baselines, the
#               expert and RRT-Connect beside the learned planner; set it
#               empty for the learned planner alone, three times faster)
#   FAMILY      the cells: standard (default; gen_SEED, the reported
#               family), wide (wide_SEED: deep boxes, tall products,
#               short lifts) or compact (compact_SEED: the products
#               beside the box); `packwright generate --help`
#   GENERATE_ARGS  more arguments for `packwright generate`: "--hand K"
#               teaches each cell by K hand-written demonstrations instead
#               of its `demos` block, "--reversed-stock" draws every suite
#               from a second inventory with the places reversed

set -euo pipefail

# The seeds reported on.
SEEDS="1000 1001 1002 1003 1004 1005 1006 1007 1008 1009 1010 1011 1012 1013 1014 1015 1016 1017 1018 1019"

cd "$(dirname "$0")/.."
bin=${PACKWRIGHT:-${CARGO_TARGET_DIR:-target}/release/packwright}
if [ ! -x "$bin" ]; then
  echo "family.sh: no binary at $bin (cargo build --release, or set PACKWRIGHT)" >&2
  exit 2
fi
if [ $# -gt 0 ]; then
  seeds=("$@")
else
  read -ra seeds <<<"$SEEDS"
fi
read -ra train_args <<<"${TRAIN_ARGS:-}"
read -ra eval_args <<<"${EVAL_ARGS---baselines}"
read -ra generate_args <<<"${GENERATE_ARGS:-}"
work=${WORK:-$(mktemp -d "${TMPDIR:-/tmp}/packwright-family.XXXXXX")}
mkdir -p "$work"

reports=()
for seed in "${seeds[@]}"; do
  # `generate` prints the file it wrote (and refuses a FAMILY it has not).
  pack=$("$bin" generate --family "${FAMILY:-standard}" --seed "$seed" -o "$work" \
    ${generate_args[@]+"${generate_args[@]}"})
  cell=$(basename "$pack" .pack)
  echo "== $cell" >&2
  "$bin" compile "$pack" -o "$work/$cell.out" >&2
  # Exit 1: some demonstration could not be replayed; the model is written.
  rc=0
  "$bin" train "$work/$cell.out" -o "$work/$cell.model" --quiet \
    ${train_args[@]+"${train_args[@]}"} >&2 || rc=$?
  if [ "$rc" -gt 1 ]; then
    echo "family.sh: training $cell failed (exit $rc)" >&2
    exit "$rc"
  fi
  "$bin" eval "$pack" --model "$work/$cell.model" --quiet \
    ${eval_args[@]+"${eval_args[@]}"} --json \
    >"$work/$cell.eval.json"
  reports+=("$work/$cell.eval.json")
done

# Summary: one row per suite and planner (SR = whole-system success rate).
echo "files in $work"
if ! command -v jq >/dev/null; then
  echo "(install jq for the summary table; the figures are in $work/*.eval.json)"
  exit 0
fi
{
  printf 'suite\tplanner\tscenarios\treasoner SR\tSR\n'
  for report in "${reports[@]}"; do
    jq -r '
      def pct: if . == null then "-" else (.rate * 100 | round / 100 | tostring) end;
      .rows[] | [.suite, .planner, .scenarios, (.reasoner_sr | pct), (.sr | pct)] | @tsv
    ' "$report"
  done
} | column -t -s $'\t'
