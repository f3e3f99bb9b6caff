#!/usr/bin/env bash
# Interim measurement of a scenario suite until `packwright eval` exists:
# runs `packwright execute` on the first COUNT cases of SUITE and prints the
# success rate (with a Wilson 95% interval), planning time per product and
# execution time per product.
#
#   scripts/measure-suite.sh "FILE..." SUITE COUNT PLANNER [SEED]
#   scripts/measure-suite.sh "../shared/examples/*/*.pack" case1_3of5 100 expert
#
# Success: every present selected product packed (by the robot or a worker)
# and no collision; missing products wait and do not count as failures.
set -euo pipefail
files=$1 suite=$2 count=$3 planner=$4 seed=${5:-1}
cd "$(dirname "$0")/.."
cargo build --release --quiet
bin="${CARGO_TARGET_DIR:-target}/release/packwright"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
width=$(( $(grep -A8 "scenarios $suite " $files 2>/dev/null | grep -m1 -oE 'count [0-9]+' | awk '{print length($2)}') + 0 ))
[ "$width" -gt 0 ] || width=${#count}
for i in $(seq 1 "$count"); do
  # shellcheck disable=SC2086
  "$bin" execute $files --scenario "$suite/$(printf "%0${width}d" "$i")" --planner "$planner" --seed "$seed" --json > "$out/$i.json" || true
done
python3 - "$out" "$suite" "$planner" <<'PY'
import glob, json, math, statistics, sys
out, suite, planner = sys.argv[1:]
ok = n = 0; plan = []; exe = []; err = []
for f in glob.glob(out + "/*.json"):
    r = json.load(open(f)); n += 1
    ok += all(p["outcome"] in ("packed", "already_packed", "waiting") for p in r["products"]) and not r["collisions"]
    for p in r["products"]:
        if p["outcome"] == "packed":
            plan.append(p["planning_ms"]); exe.append(p["execution_s"]); err.append(p["error_m"])
z = 1.96; ph = ok / n; d = 1 + z * z / n; c = (ph + z * z / (2 * n)) / d
h = z * math.sqrt(ph * (1 - ph) / n + z * z / (4 * n * n)) / d
plan.sort()
print(f"{suite} ({planner}): SR {ok}/{n} = {ph:.2f} [{c - h:.2f}, {c + h:.2f}]; "
      f"planning per product median {statistics.median(plan):.1f} ms, p99 {plan[min(len(plan) - 1, int(0.99 * len(plan)))]:.1f} ms; "
      f"execution per product {statistics.mean(exe):.2f} s (simulated); max error {max(err) * 1000:.2f} mm")
PY
