#!/usr/bin/env bash
# The two objects baselines trained again with another seed (--seed 1; everything else as
# shipped) and evaluated on the same 6,350 episodes: the paired difference between the two
# seeds of one recipe is the training run's share of a rung's difference. Resumable: run it
# again after an interruption and it continues where it stopped. One core per kind. Then it
# ships the checkpoints and compact results to docs/results/baselines/KIND-seed1 and compares
#   seeds/KIND-seed1-vs-KIND            the same recipe trained twice (the training run)
#   seeds/objects-form-seed1-vs-objects-text-seed1   the wording rung on the seed-1 networks
# Environment: DATA (the full training set), RUNS (checkpoints and runs).
set -euo pipefail
DATA=${DATA:-data/full-demos}
RUNS=${RUNS:-runs/seeds}
STEPS=120000  # as the shipped objects kinds
mkdir -p "$RUNS"
source "$(dirname "$0")/steps.sh"
lane() {  # core, kind: train seed 1, then evaluate it on every test task, 10 rounds
    local core=$1 kind=$2 ckpt="$RUNS/ckpt-$2-seed1" run="$RUNS/eval-$2-seed1"
    trained "$ckpt" "$STEPS" || taskset -c "$core" robofollow train "$DATA" \
        --policy "$kind" --seed 1 --steps "$STEPS" --out "$ckpt" --quiet \
        $(started "$ckpt/policy.json")
    [ -f "$run/summary.json" ] || taskset -c "$core" robofollow eval --policy "$ckpt" \
        --out "$run" --workers 1 --quiet $(started "$run/run.json")
}
lane 0 objects-text & lane 1 objects-form & wait

RUNS=$(realpath "$RUNS")
cd "$(dirname "$0")"
for kind in objects-text objects-form; do
    ship_checkpoint "$RUNS/ckpt-$kind-seed1" "$kind-seed1/checkpoint"
    ship_run "$RUNS/eval-$kind-seed1" "$kind-seed1"
    robofollow report "$kind-seed1" > /dev/null
    robofollow compare "$kind-seed1" "$kind" --out "seeds/$kind-seed1-vs-$kind" > /dev/null
done
robofollow compare objects-form-seed1 objects-text-seed1 \
    --out seeds/objects-form-seed1-vs-objects-text-seed1 > /dev/null
