# Sourced (not run) by the GPU scripts (gpu_many_runs.sh, gpu_session.sh) from the repository
# root: the device's environment. XLA takes GPU memory as it needs it (several processes share
# one GPU), lili comes from src/, and the wheels the device image lacks (gymnasium and its two
# dependencies, tensorboardX), carried as .whl/ (the device tool's `carry`), go to /tmp/site.
PY=${PYTHON:-python3}
export XLA_PYTHON_CLIENT_PREALLOCATE=false
export PYTHONPATH=$PWD/src
if compgen -G ".whl/*.whl" > /dev/null; then
    "$PY" -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
        --target /tmp/site .whl/*.whl && export PYTHONPATH=/tmp/site:$PWD/src
fi
