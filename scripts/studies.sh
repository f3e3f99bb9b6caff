#!/usr/bin/env bash
# The paper's generalisation studies on the repo's line2 cell
# (orders/studies/generalisation.pack): a model is taught 2 of the 5
# pantry products with a training ratio of 0.25, 0.5, 0.75 and 1 of the goal
# configurations, then `packwright eval` runs it on CASE 1 and CASE 2 with 3
# and 4 of 5 products and on missing stock (orders/suites/measure.pack), with
# no extra demonstrations. Prints one Markdown row per ratio and suite.
#
# Usage: scripts/studies.sh
# Environment:
#   PACKWRIGHT  the binary (default: target/release/packwright)
#   WORK        where the files go (default: a new directory under /tmp)
#   LIMIT       scenarios per suite (default: 100, all of them)
#   TRAIN_ARGS  extra arguments for `packwright train`
#   PLOTS       also chart the study into this directory (`packwright
#               chart`): success_vs_x.svg (reasoner success against the
#               training ratio, per suite) and success_vs_n.svg (against
#               the products in the order, per training ratio)

set -euo pipefail
cd "$(dirname "$0")/.."
bin=${PACKWRIGHT:-${CARGO_TARGET_DIR:-target}/release/packwright}
if [ ! -x "$bin" ]; then
  echo "studies.sh: no binary at $bin (cargo build --release, or set PACKWRIGHT)" >&2
  exit 2
fi
if ! command -v jq >/dev/null; then
  echo "studies.sh: jq is needed for the table" >&2
  exit 2
fi
read -ra train_args <<<"${TRAIN_ARGS:-}"
work=${WORK:-$(mktemp -d "${TMPDIR:-/tmp}/packwright-studies.XXXXXX")}
mkdir -p "$work"
suites=(m_case1_3of5 m_case1_4of5 m_case2_3of5 m_case2_4of5 m_short_3of5)

"$bin" compile orders/studies/generalisation.pack -o "$work/taught" >&2
printf '| training ratio | demos | suite | reasoner SR | SR [95%% CI] | SR no fallback |\n'
printf '|---|---|---|---|---|---|\n'
runs=()
for ratio in keep25:0.25 keep50:0.5 keep75:0.75 all:1; do
  name=study_2of5_${ratio%%:*}
  model=$work/$name.model
  echo "== $name" >&2
  rc=0
  "$bin" train "$work/taught" -o "$model" --demos "$name" --quiet \
    ${train_args[@]+"${train_args[@]}"} >&2 || rc=$?
  if [ "$rc" -gt 1 ]; then
    echo "studies.sh: training $name failed (exit $rc)" >&2
    exit "$rc"
  fi
  "$bin" eval orders/suites/measure.pack --model "$model" --suite "${suites[@]}" \
    --limit "${LIMIT:-100}" --quiet --json >"$work/$name.eval.json"
  runs+=("${ratio#*:}=$work/$name.eval.json")
  demos=$(jq -r '.demonstrations' "$model/metrics.json")
  jq -r --arg ratio "${ratio#*:}" --arg demos "$demos" '
    def f2: (. * 100 | round) as $x
      | "\($x / 100 | floor).\($x % 100 | tostring | if length < 2 then "0" + . else . end)";
    .rows[] | "| \($ratio) | \($demos) | \(.suite) (\(.scenarios)) | \(.reasoner_sr.rate | f2) | \(.sr.rate | f2) [\(.sr.ci95[0] | f2), \(.sr.ci95[1] | f2)] | \(.sr_no_fallback.rate | f2) |"
  ' "$work/$name.eval.json"
done
if [ -n "${PLOTS:-}" ]; then
  "$bin" chart "${runs[@]}" --x "training ratio" -o "$PLOTS" >&2
fi
echo "files in $work" >&2
