#!/usr/bin/env bash
# The five baselines over the whole benchmark, on a CPU, every step resumable: run it again
# after an interruption and it continues where it stopped.
#   1. the training set: every training task x 50 demonstrations (robofollow generate)
#   2. text, blind, form, objects-text and objects-form trained on all of it
#   3. each evaluated on every test task, 10 rounds; text and objects-text with an
#      empty-instruction control arm
# Environment: DATA (dataset folder), RUNS (checkpoints and runs), WORKERS (processes),
# STEPS (training steps per baseline).
set -euo pipefail
DATA=${DATA:-data/full-demos}
RUNS=${RUNS:-runs/full}
WORKERS=${WORKERS:-2}
STEPS=${STEPS:-30000}
mkdir -p "$RUNS"

started() { [ -e "$1" ] && echo "--resume" || true; }  # a folder the step already began
timed() {  # name, command...: append the step's wall time to RUNS/times.log
    local name=$1 start
    shift
    start=$(date +%s)
    "$@"
    echo "$name $(( $(date +%s) - start )) s" >> "$RUNS/times.log"
}

if [ ! -f "$DATA/manifest.json" ]; then
    timed generate robofollow generate specs --out "$DATA" --workers "$WORKERS" --quiet \
        $(started "$DATA")
fi
# Trainings run in two lanes, each pinned to one core: XLA's small convolutions scale poorly
# over cores, so two one-core runs side by side train faster than one after the other on both
# (rates measured in docs/datasets-and-training.md, "The five on the whole benchmark").
trained() { python -c "import json,sys; d=json.load(open('$1/policy.json'));
sys.exit(d['training']['steps'] < $STEPS)" 2>/dev/null; }
lane() {  # core, kinds...: train each kind in turn on that core
    local core=$1 kind ckpt
    shift
    for kind in "$@"; do
        ckpt="$RUNS/ckpt-$kind"
        trained "$ckpt" || timed "train-$kind" taskset -c "$core" robofollow train "$DATA" \
            --policy "$kind" --out "$ckpt" --steps "$STEPS" --quiet \
            $(started "$ckpt/policy.json")
    done
}
lane 0 objects-form objects-text text & first=$!
lane $(( 1 % WORKERS )) blind form & second=$!
wait "$first"
wait "$second"
for kind in objects-form objects-text text form blind; do
    run="$RUNS/eval-$kind"
    controls=()
    case $kind in text | objects-text) controls=(--controls empty) ;; esac
    if [ ! -f "$run/summary.json" ] || [ ! -f "$run/report.html" ]; then
        timed "eval-$kind" robofollow eval --policy "$RUNS/ckpt-$kind" --out "$run" \
            --workers "$WORKERS" --quiet "${controls[@]}" $(started "$run/run.json")
    fi
done
