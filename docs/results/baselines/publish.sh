#!/usr/bin/env bash
# After full-benchmark.sh: ship the five checkpoints and their compact results.
#   robofollow/baselines/KIND         policy.json, params.npz, training.jsonl (the same bytes as
#                                     RUNS/ckpt-KIND; the optimizer state stays behind)
#   docs/results/baselines/KIND       run.json, summary.json, scores.csv.gz (and controls/empty)
#                                     of RUNS/eval-KIND, with its rebuilt report
#   docs/results/baselines/full       Table 1 of the five side by side
#   docs/results/baselines/ladder/*   the diagnosis ladder's paired comparisons
# Environment: RUNS (as for full-benchmark.sh).
set -euo pipefail
cd "$(dirname "$0")/../../.."
RUNS=${RUNS:-runs/full}
OUT=docs/results/baselines
KINDS="text blind form objects-text objects-form"
source docs/results/baselines/steps.sh

for kind in $KINDS; do
    ship_checkpoint "$RUNS/ckpt-$kind" "robofollow/baselines/$kind"
    for arm in "" controls/empty; do
        [ -d "$RUNS/eval-$kind/$arm" ] || continue
        ship_run "$RUNS/eval-$kind/$arm" "$OUT/$kind/$arm"
    done
    if [ -d "$OUT/$kind/controls/empty" ]; then
        robofollow report "$OUT/$kind/controls/empty" > /dev/null
    fi
    robofollow report "$OUT/$kind" > /dev/null  # with the language effect, where it has a control
done

robofollow report $(for kind in $KINDS; do echo "$OUT/$kind"; done) --out "$OUT/full"
# each rung: A - B
for rung in text:blind objects-text:text objects-form:objects-text form:text; do
    a=${rung%:*} b=${rung#*:}
    robofollow compare "$OUT/$a" "$OUT/$b" --out "$OUT/ladder/$a-vs-$b" > /dev/null
done
