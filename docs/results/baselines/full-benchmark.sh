#!/usr/bin/env bash
# The five baselines over the whole benchmark, on a CPU, every step resumable: run it again
# after an interruption and it continues where it stopped.
#   1. the training set: every training task x 50 demonstrations (robofollow generate)
#   2. text, blind, form, objects-text and objects-form trained on all of it
#   3. each evaluated on every test task, 10 rounds; text and objects-text with an
#      empty-instruction control arm
# Environment: DATA (dataset folder), RUNS (checkpoints and runs), WORKERS (cores, one lane
# each: 1 or 2), STEPS (training steps of the image kinds), OBJECT_STEPS (of the objects
# kinds), PARTS (shards per evaluation).
set -euo pipefail
DATA=${DATA:-data/full-demos}
RUNS=${RUNS:-runs/full}
WORKERS=${WORKERS:-2}
STEPS=${STEPS:-60000}
OBJECT_STEPS=${OBJECT_STEPS:-120000}
PARTS=${PARTS:-8}
mkdir -p "$RUNS/parts"
source "$(dirname "$0")/steps.sh"

timed() {  # name, command...: append the step's wall time to RUNS/times.log
    local name=$1 start
    shift
    start=$(date +%s)
    "$@" || return
    echo "$name $(( $(date +%s) - start )) s" >> "$RUNS/times.log"
}

if [ ! -f "$DATA/manifest.json" ]; then
    timed generate robofollow generate specs --out "$DATA" --workers "$WORKERS" --quiet \
        $(started "$DATA")
fi

# Trainings run in two lanes, each pinned to one core: XLA's small convolutions scale poorly
# over cores, so two one-core runs side by side train faster than one after the other on both
# (rates measured in docs/datasets-and-training.md, "The five on the whole benchmark").
steps() { case $1 in objects-*) echo "$OBJECT_STEPS" ;; *) echo "$STEPS" ;; esac; }
kind_trained() { trained "$RUNS/ckpt-$1" "$(steps "$1")"; }
train() {  # core, kinds...: train each kind in turn on that core
    local core=$1 kind ckpt
    shift
    for kind in "$@"; do
        ckpt="$RUNS/ckpt-$kind"
        kind_trained "$kind" || timed "train-$kind" taskset -c "$core" robofollow train "$DATA" \
            --policy "$kind" --out "$ckpt" --steps "$(steps "$kind")" --quiet \
            $(started "$ckpt/policy.json")
    done
}

# Every evaluation (and control arm) runs in PARTS shards. A lane whose trainings are done
# takes the next shard no other lane holds (flock) whose checkpoint is trained, so neither
# core idles while shards are left; the shards are merged into one run at the end.
ARMS="objects-form:normal objects-text:normal objects-text:empty text:normal text:empty
blind:normal form:normal"
done_run() { [ -f "$1/summary.json" ] && [ -f "$1/report.html" ]; }
evaluate() {  # core: evaluate shards until none is left
    local core=$1 arm kind mode i part left rc
    while :; do
        left=0
        for arm in $ARMS; do
            kind=${arm%:*} mode=${arm#*:}
            for i in $(seq 1 "$PARTS"); do
                part="$RUNS/parts/eval-$kind-$mode-$i"
                done_run "$part" && continue
                left=1
                kind_trained "$kind" || continue
                rc=0
                (
                    flock -n 9 || exit 75  # another lane has this shard
                    done_run "$part" && exit 0  # or had it, since the check above
                    timed "eval-$kind-$mode-$i" taskset -c "$core" robofollow eval \
                        --policy "$RUNS/ckpt-$kind" --out "$part" --quiet --workers 1 \
                        --instruction-mode "$mode" --shard "$i/$PARTS" \
                        $(started "$part/run.json")
                ) 9> "$part.lock" || rc=$?
                [ "$rc" = 0 ] || [ "$rc" = 75 ] || return "$rc"
            done
        done
        [ "$left" = 0 ] && return
        sleep 60  # the shards left wait for a training or for the other lane
    done
}
lane() { train "$@"; evaluate "$1"; }
lane 0 objects-text objects-form blind & first=$!
lane $(( 1 % WORKERS )) text form & second=$!
wait "$first"
wait "$second"

for arm in $ARMS; do
    kind=${arm%:*} mode=${arm#*:}
    run="$RUNS/eval-$kind"
    [ "$mode" = normal ] || run="$run/controls/$mode"
    [ -f "$run/summary.json" ] || robofollow merge --out "$run" \
        $(for i in $(seq 1 "$PARTS"); do echo "$RUNS/parts/eval-$kind-$mode-$i"; done)
    # a control arm: the run's report again, with the language effect
    [ "$mode" = normal ] || robofollow report "$RUNS/eval-$kind" > /dev/null
done
