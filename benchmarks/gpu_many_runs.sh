#!/usr/bin/env bash
# One measurement of the many-runs paths on a GPU machine (issue 33), run once from the
# repository root:
#
#     OUT=/some/folder bash benchmarks/gpu_many_runs.sh        # SMOKE=1: tiny sizes, any CPU
#
# Point Mass, the paper's sizes: the JAX-native path (lili.jax_train) for LILI and SAC at
# K = 1 .. 4096 runs in one program, the Gymnasium path (lili.many) for LILI at K = 1, 16, 64,
# and K = 72 LILI runs timed for a few hundred interactions and extrapolated to the paper's
# budget of 2000 (the issue's "72 runs in <= 15 minutes"; labelled extrapolated in its JSON).
# It also trains 8 seeds of LILI for the paper's 2000 interactions through `lili train
# --backend jax` (run folders, logging and checkpoints included) and summarises their returns.
# Every step has its own time limit and the whole stays under BUDGET seconds (default 400);
# benchmarks/many_runs.py writes its JSON after every row, so a step cut short keeps what it
# measured. Writes into $OUT: log.txt and at most 6 JSON files.
# Wheels the device lacks come from .whl/ (benchmarks/gpu_env.sh).
set -o pipefail
cd "$(dirname "$0")/.."
OUT=${OUT:-/tmp/gpu_many_runs}
BUDGET=${BUDGET:-400}
mkdir -p "$OUT"
LOG="$OUT/log.txt"
START=$(date +%s)
source benchmarks/gpu_env.sh
export XLA_PYTHON_CLIENT_MEM_FRACTION=0.9
# Steps that compile the same program (same K and sizes) reuse it from this cache.
export JAX_COMPILATION_CACHE_DIR=${JAX_COMPILATION_CACHE_DIR:-/tmp/jax_cache_many_runs}

{ date -u; nvidia-smi 2>&1 | head -20; nproc; free -g | head -2
  "$PY" -c "import jax, platform; print('jax', jax.__version__, jax.devices(), platform.platform())"
  "$PY" -c "import lili.jax_train, lili.many; print('lili imports: ok')"
} 2>&1 | tee "$LOG"

if [ "${SMOKE:-0}" = 1 ]; then
    CONFIG=$(mktemp --suffix=.yaml)
    printf 'hidden: [32, 32]\nenc_hidden: [16, 16]\nwarmup_interactions: 3\nbuffer_capacity: 50\nbatch_interactions: 4\nper_interaction: 4\nupdates_per_step: 0.1\ncheckpoint_every: 5\n' > "$CONFIG"
    SIZE=(--config "$CONFIG")
    JAX_KS=(2); JAX_NS=(2); SAC_KS=(2); SAC_NS=(2); GYM_KS=(2); GYM_NS=(2)
    K72=2; N72=3; LEARN_SEEDS=0-1; LEARN_N=12
    CAPS=(900 900 900 900 900)
else
    SIZE=()
    # The largest K first after K = 1, so that a step cut short by its time limit loses the
    # middle of the table, not its ends.
    JAX_KS=(1 1024 4096 128 16); JAX_NS=(30 5 3 10 20)
    SAC_KS=(1 1024 4096 128); SAC_NS=(30 5 3 10)
    GYM_KS=(1 16 64); GYM_NS=(3 2 2)
    K72=72; N72=200; LEARN_SEEDS=0-7; LEARN_N=2000
    CAPS=(135 60 85 60 60)
fi

# step NAME CAP ARGS...: benchmarks/many_runs.py with at most CAP seconds and what is left.
step() {
    local name=$1 cap=$2; shift 2
    local left=$(( BUDGET - ($(date +%s) - START) ))
    (( cap > left )) && cap=$left
    if (( cap < 25 )); then echo "skipped $name: the time budget is spent" | tee -a "$LOG"; return; fi
    echo "== $name (at most $cap s): $*" | tee -a "$LOG"
    timeout --kill-after=10 "$cap" "$@" 2>&1 | tee -a "$LOG"
    echo "   rc=${PIPESTATUS[0]} after $(( $(date +%s) - START )) s" | tee -a "$LOG"
}
bench() { local name=$1 cap=$2; shift 2
    step "$name" "$cap" "$PY" benchmarks/many_runs.py --name "$name" --out-dir "$OUT" "${SIZE[@]}" "$@"; }

# K = 4096 runs' buffers (10,000 interactions each) are 60 GB: let them take 80% of the GPU.
bench jax_lili "${CAPS[0]}" --path jax --algo lili --ks "${JAX_KS[@]}" --interactions "${JAX_NS[@]}" --budget 2000 --memory-fraction 0.8
bench jax_lili_k72 "${CAPS[1]}" --path jax --algo lili --ks "$K72" --interactions "$N72" --budget 2000

# End to end through the command: LILI learning Point Mass, 8 seeds in one program, run folders
# and all; summarised from the metrics.csv files (whatever a time limit left of them).
RUNS=$(mktemp -d)
step jax_learning "${CAPS[2]}" "$PY" -m lili.cli train point-mass --backend jax --algo lili \
    --seeds "$LEARN_SEEDS" --interactions "$LEARN_N" --out "$RUNS" --no-progress "${SIZE[@]}"
"$PY" - "$RUNS" "$OUT/jax_learning.json" "$LEARN_N" "${SIZE[*]:-paper sizes}" <<'PY' 2>&1 | tee -a "$LOG"
import csv, json, sys
from pathlib import Path
runs, out, budget, sizes = Path(sys.argv[1]), Path(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
seeds = {}
for m in sorted(runs.glob("*/*/seed_*/metrics.csv")):
    rows = list(csv.DictReader(m.open()))
    ret = [float(r["return"]) for r in rows]
    own = [float(r["return"]) for r in rows if r["random"] == "0"]
    seeds[m.parent.name] = {
        "interactions": len(rows), "wall_s": float(rows[-1]["wall_time"]) if rows else None,
        "random_warmup_mean": sum(ret[:20]) / max(1, len(ret[:20])),
        "first_100_policy_mean": sum(own[:100]) / max(1, len(own[:100])),
        "last_200_mean": sum(ret[-200:]) / max(1, len(ret[-200:])),
        "finished": (m.parent / "summary.json").exists()}
res = {"what": "lili train point-mass --backend jax --algo lili, metrics.csv of each seed",
       "sizes": sizes, "budget": budget, "seeds": seeds}
out.write_text(json.dumps(res, indent=2) + "\n")
print(json.dumps(res))
PY

bench gym_lili "${CAPS[3]}" --path gym --algo lili --ks "${GYM_KS[@]}" --interactions "${GYM_NS[@]}"
bench jax_sac "${CAPS[4]}" --path jax --algo sac --ks "${SAC_KS[@]}" --interactions "${SAC_NS[@]}" --budget 2000 --memory-fraction 0.8
nvidia-smi --query-gpu=name,memory.used,memory.total --format=csv 2>&1 | tee -a "$LOG"
echo "done in $(( $(date +%s) - START )) s; files in $OUT:" | tee -a "$LOG"
ls -la "$OUT" | tee -a "$LOG"
