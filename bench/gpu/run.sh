#!/usr/bin/env bash
# On the lent GPU machine, from the repository root (bench/gpu/README.md says how it gets
# there): put the carried warp-lang parts together, install it beside the image's own
# packages, and run the CUDA checks and the GPU benchmarks, most wanted first, within 500 s
# (the call's limit is 540 s). Everything goes to $OUT (at most seven files).
set -uo pipefail
OUT=${OUT:-/tmp/tightknot-gpu}
BUDGET=${BUDGET:-500}
mkdir -p "$OUT"
log() { echo "== $*" | tee -a "$OUT/run.log"; }
# seconds a step may take: its own cap, or what is left of the budget
cap() { local left=$((BUDGET - SECONDS)); echo $(( left < $1 ? (left > 1 ? left : 1) : $1 )); }
name=$(cat .whl/wheel.name)
cat .whl/wheel.part* > "/tmp/$name"
echo "$(cat .whl/wheel.sha256)  /tmp/$name" | sha256sum -c - >> "$OUT/run.log" 2>&1 || {
    log "the carried warp-lang parts do not add up to the wheel (a part missing?)"; exit 3; }
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --target /tmp/site \
    "/tmp/$name" >> "$OUT/run.log" 2>&1 || { log "pip install of $name failed"; exit 4; }
export PYTHONPATH=/tmp/site:$PWD WARP_CACHE_PATH=/tmp/warp-cache
TK=(python3 -c 'import sys; from tightknot.app.cli import main; sys.exit(main(sys.argv[1:]))')
nvidia-smi >> "$OUT/run.log" 2>&1
log "warp devices: $(python3 -c 'import warp as wp; wp.init(); print([d.alias for d in wp.get_devices()])' 2>&1 | tail -1)"
log "pytest -m cuda"
timeout "$(cap 240)" python3 -m pytest -q -p no:cacheprovider -m cuda tests/test_devices.py \
    > "$OUT/pytest_cuda.txt" 2>&1; log "exit $? at ${SECONDS} s"
step() {  # step CAP NAME ARGS...: one benchmark, its output in run.log
    local c=$1 n=$2; shift 2
    log "bench $n"
    timeout "$(cap "$c")" "${TK[@]}" bench "$@" >> "$OUT/run.log" 2>&1
    log "exit $? at ${SECONDS} s"
}
step 90 "contact cuda:0" contact --device cuda:0 --json "$OUT/contact_cuda.json"
step 180 "batch cuda:0 (one by one: 8 of 64 rods, extrapolated)" batch --device cuda:0 \
    --sequential-rods 8 --json "$OUT/batch_cuda.json"
step 90 "der cuda:0" der --device cuda:0 --sizes 1000 10000 100000 --no-startup \
    --json "$OUT/der_cuda.json"
step 60 "contact cpu" contact --device cpu --json "$OUT/contact_cpu.json"
step 60 "der cpu" der --device cpu --sizes 1000 10000 100000 --no-startup \
    --json "$OUT/der_cpu.json"
