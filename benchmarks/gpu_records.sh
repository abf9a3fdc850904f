#!/usr/bin/env bash
# Superseded by benchmarks/gpu_session.sh, the one table of the Point Mass runs trained on a GPU
# (its header says what each part is and how to call it); kept so that the journal's commands
# still run: ALGOS="sac oracle" (the default) trains those parts' cells, LONG=1 the
# 4000-interaction LILI cells.
if [ "${LONG:-0}" = 1 ]; then PARTS=long; else PARTS=${ALGOS:-sac oracle}; fi
PARTS=$PARTS exec bash "$(dirname "$0")/gpu_session.sh"
