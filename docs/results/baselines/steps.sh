# Shell steps shared by full-benchmark.sh, second-seed.sh and publish.sh (sourced, not run).
started() { [ -e "$1" ] && echo "--resume" || true; }  # a folder the step already began
trained() {  # checkpoint, steps: whether it has trained that many steps
    python -c "import json,sys; d=json.load(open('$1/policy.json'));
sys.exit(d['training']['steps'] < $2)" 2>/dev/null
}
# What ships of a checkpoint (its optimizer state stays behind) and of a run.
ship_checkpoint() { mkdir -p "$2" && cp "$1/"{policy.json,params.npz,training.jsonl} "$2/"; }
ship_run() { mkdir -p "$2" && cp "$1/"{run.json,summary.json,scores.csv.gz} "$2/"; }
