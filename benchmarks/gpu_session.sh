#!/usr/bin/env bash
# Point Mass trainings for a GPU, in one call of at most 9 minutes:
#
#     OUT=/some/folder bash benchmarks/gpu_session.sh     # SMOKE=1: tiny budget, any CPU
#                                                         # DRY=1: print the commands only
#
# One `lili train point-mass --backend jax` process per line of the table below (the JAX twin
# of Point Mass, lili.jax_train: the seeds of a line are one program; config.yaml says
# `backend: jax`), all started at once and sharing the GPU (no XLA preallocation). Its parts
# (PARTS, default "collapse critic-ln variants", the ones that still wait on a GPU):
#
#   oracle     the Oracle against the noisy partner (sigma 0.4, 1.0) and the history-dependent
#              one (N = 5, 11), seeds 0-2, 2000 interactions: the noise and history tables'
#              missing Oracle cells (issue 34; done on a CPU in s32, records s32/noise-oracle
#              and s32/history-oracle; not in the default)
#   long       LILI at sigma 0.2, 0.6, 1.0, seeds 0-2, 4000 interactions: the noise table's
#              check that ours sits below the paper because its curves still rise at 2000
#              (issue 34), under noise-4000/ (done on a CPU in s34 on the Gymnasium path,
#              records s34/noise-4000; not in the default)
#   collapse   Point Mass LILI (the current core), seeds 7-13, 2000 interactions: is critic
#              divergence or the target's escape the usual collapse mode (issue 36, item 4;
#              journal "Point Mass LILI's late collapses"; seeds 0-6 are s9/point-mass)
#   critic-ln  the candidate fix for critic divergence, LILI with LayerNorm in its critic
#              (lili.contrib.critics, algo lili-critic-ln), seeds 0-13, 2000 interactions, as
#              two processes of 7 seeds
#   variants   the two variants that got past LILI's local optimum on Flee (issue 36, item 3;
#              journal s29), lili-prediction-critic and lili-set-encoder, on Point Mass at
#              seeds 7-13 (the collapse part's LILI seeds: paired, same path), 2000
#              interactions: do they cost anything on the paper's influence domain?
#   sac        SAC in the oracle part's four cells (done: s26's records; not in the default)
#
# The run folders land in the layout of `lili reproduce` (noise/sigma_0.4/PointMass-v0/oracle/
# seed_0, history/n_5/..., noise-4000/sigma_0.2/PointMass-v0/lili/seed_0, point-mass/
# PointMass-v0/lili/seed_7, point-mass/PointMass-v0/lili-critic-ln/seed_0, ...) and come back
# as $OUT/records.tar.gz holding each run's config.yaml, metrics.csv and summary.json (no
# checkpoints, no TensorBoard), beside $OUT/log.txt (each process's exit code and its last
# lines). Every process has the same time limit, CAP seconds (default 480), after which it is
# interrupted as Ctrl-C would (its loggers close); a run cut short keeps its metrics.csv and has
# no summary.json. No process runs past START + CAP + 15 s; the whole, with the wheels' install
# and the tarball, stays under 9 minutes.
#
# Time estimate, from the journal ("Many runs on one H200 (issue 33)", "The noise and history
# tables' SAC cells, on a GPU"); none of it measured with twelve processes at once:
# - compile and warm-up 32-39 s per program (twelve compiling at once on 16 cores: say 60 s);
# - one Point Mass LILI interaction of K runs in one program: 16 ms at K = 1, 70 ms at K = 72;
#   through `lili train` with its run folders about 17 interactions a second per process
#   (K = 8, alone on the GPU: 1074 interactions in 60 s);
# - s26: four SAC processes (K = 3) beside four Gymnasium-path Oracle processes on one GPU ran
#   2000 interactions in 126-129 s of training (the program's compile included).
# So at 17 interactions a second: each 2000-interaction line (4 Oracle, 1 LILI, 2 LILI-LN,
# 2 variants; K = 3 or 7) 60 + 120 = 180 s, each 4000-interaction LILI line 60 + 235 = 295 s;
# with all twelve at once (every part) about 5 minutes if sharing the GPU costs them little.
# CAP = 480 s gives the 4000-interaction lines 1.6x that for the contention (the
# 2000-interaction lines end first and leave the GPU to them). GPU time of the call: at most CAP + about 30 s
# (wheels, jax's start, tarball) = 8.5 minutes, plus the machine's start (1-2 minutes) and the
# transfers.
#
# For the coordinator, from the main checkout's root (the device `run` tool sends the checkout
# the session started in, at most 64 MiB):
#   1. mv benchmarks/results/runs /work/runs-hold     # 109 MiB of records; the tree must be < 64
#   2. device run, carry [".whl"] (the wheels: gymnasium, cloudpickle, farama-notifications,
#      tensorboardX in /work/main/.whl, ignored by .git/info/exclude), timeout_s 560:
#          bash benchmarks/gpu_session.sh
#      ($OUT is set by the tool; the files come back under the reply's files_at.)
#   3. mv /work/runs-hold benchmarks/results/runs     # at once, whatever the call returned
#   4. mkdir -p benchmarks/results/runs/sNN/gpu-session && tar xzf FILES_AT/records.tar.gz -C
#      benchmarks/results/runs/sNN/gpu-session     # NN: that session's number; keep log.txt
#      beside it as gpu-session/log.txt
#   5. read them: `lili report DIR --out DIR/report` for noise/sigma_*, history/n_*,
#      noise-4000/sigma_*, point-mass; `python benchmarks/collapse_records.py
#      benchmarks/results/runs/s9/point-mass/PointMass-v0/lili DIR/point-mass/PointMass-v0/lili
#      DIR/point-mass/PointMass-v0/lili-critic-ln` (each folder one group; seeds 7-13 of LILI
#      and all of LILI-LN are JAX-path runs, whose partner draws differ from the Gymnasium
#      path's of s9); the journal gets the numbers.
set -o pipefail
cd "$(dirname "$0")/.."
OUT=${OUT:-/tmp/gpu_session}
CAP=${CAP:-480}
PARTS=${PARTS:-collapse critic-ln variants}
for part in $PARTS; do
    case $part in oracle|sac|long|collapse|critic-ln|variants) ;;
        *) echo "gpu_session.sh: PARTS names '$part'; allowed: oracle, sac, long, collapse," \
               "critic-ln, variants" >&2; exit 2;;
    esac
done
LOG="$OUT/log.txt"
START=$(date +%s)
if [ "${DRY:-0}" != 1 ]; then  # a dry run writes nothing and installs nothing
    mkdir -p "$OUT"
    source benchmarks/gpu_env.sh
    RUNS=$(mktemp -d)
    mkdir -p "$RUNS/logs"
fi
if [ "${SMOKE:-0}" = 1 ]; then
    # Learning after a 3-interaction warm-up, small nets: every path of the program runs. Only
    # fields every algo here reads (a --config is checked against the algo).
    SMALL=$(mktemp --suffix=.yaml)
    printf 'hidden: [16, 16]\nwarmup_interactions: 3\nbuffer_capacity: 20\nbatch_interactions: 4\nper_interaction: 4\nupdates_per_step: 0.04\ncheckpoint_every: 2\n' > "$SMALL"
fi
[ "${DRY:-0}" = 1 ] || { date -u; nvidia-smi --query-gpu=name,memory.total --format=csv 2>&1
  "$PY" -c "import jax; print('jax', jax.__version__, jax.devices())"; } 2>&1 | tee "$LOG"

# line PART FOLDER ALGO SEEDS INTERACTIONS [ENV_KWARG]: one process, if PART is asked for.
pids=() names=()
line() {
    local part=$1 folder=$2 algo=$3 seeds=$4 n=$5 kw=${6:-}
    [[ " $PARTS " == *" $part "* ]] || return 0
    local args=(--seeds "$seeds" --interactions "$n")
    if [ "${SMOKE:-0}" = 1 ]; then  # two seeds of the line, 5 interactions
        local first=${seeds%-*}
        args=(--seeds "$first-$((first + 1))" --interactions 5 --config "$SMALL")
    fi
    [ -n "$kw" ] && args+=(--env-kwarg "$kw")
    local name="${folder//\//_}-$algo-$seeds"
    if [ "${DRY:-0}" = 1 ]; then echo "lili train point-mass --algo $algo ${args[*]} --out" \
        "RUNS/$folder --no-progress --backend jax"; return 0; fi
    timeout -s INT --kill-after=15 "$CAP" "$PY" -m lili.cli train point-mass --algo "$algo" \
        "${args[@]}" --out "$RUNS/$folder" --no-progress --backend jax \
        > "$RUNS/logs/$name.log" 2>&1 &
    pids+=($!) names+=("$name")
}

for algo in oracle sac; do
    line "$algo" noise/sigma_0.4 "$algo" 0-2 2000 step_noise=0.4
    line "$algo" noise/sigma_1 "$algo" 0-2 2000 step_noise=1.0
    line "$algo" history/n_5 "$algo" 0-2 2000 history=5
    line "$algo" history/n_11 "$algo" 0-2 2000 history=11
done
line long noise-4000/sigma_0.2 lili 0-2 4000 step_noise=0.2
line long noise-4000/sigma_0.6 lili 0-2 4000 step_noise=0.6
line long noise-4000/sigma_1 lili 0-2 4000 step_noise=1.0
line collapse point-mass lili 7-13 2000
line critic-ln point-mass lili-critic-ln 0-6 2000
line critic-ln point-mass lili-critic-ln 7-13 2000
line variants point-mass lili-prediction-critic 7-13 2000
line variants point-mass lili-set-encoder 7-13 2000

[ "${DRY:-0}" = 1 ] && exit 0
echo "${#pids[@]} processes (parts: $PARTS), at most $CAP s each" | tee -a "$LOG"
for i in "${!pids[@]}"; do
    wait "${pids[$i]}"
    echo "${names[$i]}: rc=$? after $(( $(date +%s) - START )) s" | tee -a "$LOG"
done
for f in "$RUNS"/logs/*.log; do
    echo "== ${f##*/}"; tail -n 4 "$f"
done | sed "s#$RUNS#RUNS#g" >> "$LOG"
(cd "$RUNS" && find . \( -name config.yaml -o -name metrics.csv -o -name summary.json \) \
    -path '*seed_*' | sort | tar czf "$OUT/records.tar.gz" -T -)
echo "finished runs: $(find "$RUNS" -name summary.json | wc -l) of $(find "$RUNS" \
    -name metrics.csv | wc -l); $(( $(date +%s) - START )) s in all" | tee -a "$LOG"
