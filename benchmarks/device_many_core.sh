#!/usr/bin/env bash
# Issue #30's many-core figures on a lent device, in one command (benchmarks/README.md,
# "Many-core figures on a lent device"): the batch's scaling over 1…16 workers
# (bench_fleet.py), then the CSV and LAS readers against the pyarrow floor at 1…16 threads
# (bench_csv.py, bench_las.py --lasio-rounds 0), each under its own time limit.
#
#     bash benchmarks/device_many_core.sh          # full sizes: ~4 min on 16 cores, at most 8.5
#     bash benchmarks/device_many_core.sh quick    # a few wells and rows: a check that it runs
#
# Needs the wheels of benchmarks/device_wheels.sh in .whl (carried) and no network: installs
# them into /tmp/site, runs gyropipe from src/ (a console-script shim on PATH for
# bench_fleet's simulate step), and writes one log a step to $OUT (default /tmp/devout).
# DEVICE_TMP (default /tmp) holds the install, the shim and the simulated wells.
set -uo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.." || exit
mode=${1:-full}
out=${OUT:-/tmp/devout}
python=${PYTHON:-python3}
tmp=${DEVICE_TMP:-/tmp} # the wheels installed, the shim, the simulated wells
site=$tmp/site
data=$tmp/gyropipe-bench-fleet
mkdir -p "$out"
case $mode in
full)
    fleet=(--wells 128 --workers-list "1,2,4,8,16")
    csv=()
    las=(--lasio-rounds 0)
    limits=(240 150 110)
    ;;
quick)
    fleet=(--wells 6 --seeds 2 --workers-list "1,2")
    csv=(--rows 50000 --floor-rounds 2 --rounds 1 --threads 1 2)
    las=(--lasio-rounds 0 --rows 50000 --rounds 2 --threads 1 2)
    limits=(120 60 60)
    ;;
*)
    echo "usage: $0 [full|quick]" >&2
    exit 2
    ;;
esac

"$python" -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
    --target "$site" .whl/*.whl || exit
export PYTHONPATH=$site:$PWD/src PYTHONUNBUFFERED=1
shim=$tmp/gyropipe-bin
mkdir -p "$shim"
printf '#!%s\nimport sys\n\nfrom pipeline.cli import main\n\nsys.exit(main())\n' \
    "$("$python" -c 'import sys; print(sys.executable)')" >"$shim/gyropipe"
chmod +x "$shim/gyropipe"
export PATH=$shim:$PATH

{
    date -u
    echo "nproc $(nproc); affinity $("$python" -c 'import os; print(len(os.sched_getaffinity(0)))')"
    lscpu | grep -E '^(Model name|Socket|Core|Thread|CPU\(s\)|NUMA node\(s\)|L2|L3|CPU max MHz)'
    free -g
    uptime
    df -h "$tmp" | tail -1
    "$python" -VV
    gyropipe --version
    "$python" benchmarks/device_deps.py check
} 2>&1 | tee "$out/machine.log"

status=() failed=0
step() { # NAME LIMIT_S COMMAND…: the command's output to $out/NAME.log, killed at LIMIT_S
    local name=$1 limit=$2
    shift 2
    echo "== $name ($mode, limit ${limit} s, $(date -u +%T)): $*"
    SECONDS=0
    timeout -k 10 "$limit" "$@" 2>&1 | tee "$out/$name.log"
    local rc=${PIPESTATUS[0]}
    [ "$rc" -eq 0 ] || failed=1
    status+=("$name rc=$rc ${SECONDS} s$([[ $rc == 124 || $rc == 137 ]] && echo ' (time limit)')")
    echo "== $name: rc=$rc after ${SECONDS} s; load $(cut -d' ' -f1-3 /proc/loadavg)"
}
step fleet "${limits[0]}" "$python" benchmarks/bench_fleet.py --data "$data" "${fleet[@]}"
[ -s "$data/runs/batch.log" ] && tail -c 1000000 "$data/runs/batch.log" >"$out/fleet-batch.log"
step csv "${limits[1]}" "$python" benchmarks/bench_csv.py "${csv[@]}"
step las "${limits[2]}" "$python" benchmarks/bench_las.py "${las[@]}"

{
    echo "== summary ($mode, $(nproc) cores, $(date -u +%T))"
    printf '%s\n' "${status[@]}"
    grep -A30 '^ *workers  *wall s' "$out/fleet.log"
    grep -E '^\((a|b)\) (at|pandas)|^largest' "$out/csv.log"
    grep -E '^ours / ' "$out/las.log"
} 2>&1 | tee "$out/summary.log"
exit "$failed"
