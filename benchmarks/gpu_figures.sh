#!/usr/bin/env bash
# The GPU figures of the open issues in one prepared call (issue 7 item 6: MPM 3D Johnson-Cook throughput;
# issue 5 item 7: Eulerian 3D throughput at 256^3; issue 8 items 3 and 5: he-slab-2d against he-slab-2d-mpm
# and he-slab-3d wall times; benchmarks/gpu_profile.py: kernel time against wall time), each stage under
# its own time limit so one slow stage cannot take the others.
#
#   bash benchmarks/gpu_figures.sh STAGES...   stages: env mpm mpm-sort euler slab2d slab2d-cache slab3d profile runprof tests
#                                                (default: all but mpm-sort, slab2d-cache, profile and runprof)
#
# Logs and JSON rows go to $OUT (default /tmp/gpu_figures): log.txt, results_mpm_gpu.json,
# results_euler_gpu.json, <run>_summary.json, profile_gpu.json, profile_run_gpu.json. SMALL=1 shrinks every problem for a dry run on a CPU.
# Python packages the GPU machine lacks travel as wheels in .whl/ (pydantic, tomli-w, ...): installed to
# /tmp/site when that folder exists.
set -u
OUT=${OUT:-/tmp/gpu_figures}
mkdir -p "$OUT"
LOG=$OUT/log.txt
ROOT=$(cd "$(dirname "$0")/.." && pwd)
cd "$ROOT"
if [ -d .whl ]; then
  python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl \
    || exit 1
  export PYTHONPATH=/tmp/site
fi
export PYTHONPATH=$ROOT/src:$ROOT/benchmarks:${PYTHONPATH:-}
export PYTHONUNBUFFERED=1
PY=${PY:-python3}
if [ "${SMALL:-0}" = 1 ]; then
  MPM_CELLS="8"; MPM_PROFILE_CELLS=8; EULER_SIZES="16"; MIN_TIME=0.2; SLAB_END=3e-6; SLAB3D_END=1e-6
else
  MPM_CELLS="80"; MPM_PROFILE_CELLS=80; EULER_SIZES="256"; MIN_TIME=2; SLAB_END=""; SLAB3D_END=""
fi

stage() {  # stage NAME LIMIT_S COMMAND...: output to the log, a line with its exit status and wall time
  local name=$1 limit=$2 t0=$SECONDS
  shift 2
  echo "=== $name (limit ${limit} s) $(date -u +%T)" | tee -a "$LOG"
  timeout "$limit" "$@" >>"$LOG" 2>&1
  echo "=== $name rc $? in $((SECONDS - t0)) s" | tee -a "$LOG"
}

slab_runs() {  # the Fig. 12 pair (docs/figures/make_000_figures.py RUNS) to 32.5 us: steps, wall and compile time
  $PY - "$OUT" "$SLAB_END" "$@" <<'EOF'
import json, shutil, sys
from pathlib import Path
import jax
import blastfsi
sys.path.insert(0, "docs/figures")
from make_000_figures import RUNS
out, end, names = Path(sys.argv[1]), sys.argv[2], sys.argv[3:]
print("device", jax.devices()[0], flush=True)
for name in names:
    example, overrides = RUNS[name]
    overrides = dict(overrides, **({"time.end": float(end)} if end else {}))
    folder = Path("/tmp/gpu_runs") / name
    shutil.rmtree(folder, ignore_errors=True)
    res = blastfsi.run(example, set=overrides, out=folder)
    keep = {k: v for k, v in res.summary.items() if isinstance(v, (int, float, str, bool))}
    (out / f"{name}_summary.json").write_text(json.dumps(res.summary, indent=1, default=str))
    print(name, json.dumps({k: keep.get(k) for k in ("steps", "wall_time", "loop_time", "output_time", "compile_time",
                                                      "particles")}), flush=True)
EOF
}

slab3d_run() {
  $PY - "$OUT" "$SLAB3D_END" <<'EOF'
import json, shutil, sys
from pathlib import Path
import jax
import blastfsi
out, end = Path(sys.argv[1]), sys.argv[2]
print("device", jax.devices()[0], flush=True)
folder = Path("/tmp/gpu_runs/he-slab-3d")
shutil.rmtree(folder, ignore_errors=True)
res = blastfsi.run("he-slab-3d", set={"time.end": float(end)} if end else {}, out=folder)
(out / "he-slab-3d_summary.json").write_text(json.dumps(res.summary, indent=1, default=str))
print("he-slab-3d", json.dumps({k: res.summary.get(k) for k in ("steps", "wall_time", "compile_time", "particles")}))
EOF
}

export -f slab_runs slab3d_run
export PY OUT SLAB_END SLAB3D_END
STAGES=${*:-env mpm euler slab2d slab3d tests}
for s in $STAGES; do
  case $s in
    env) stage env 120 bash -c "nvidia-smi --query-gpu=name,memory.total,clocks.sm,clocks.mem --format=csv; \
$PY -c 'import jax, jaxlib, numpy; print(jax.__version__, jaxlib.__version__, numpy.__version__, jax.devices())'" ;;
    mpm) stage mpm 300 $PY benchmarks/bench_mpm.py --cells $MPM_CELLS --precision float64 float32 --repeats 3 \
           --min-time $MIN_TIME --label gpu --out "$OUT/results_mpm_gpu.json" ;;
    mpm-sort) stage mpm-sort 200 $PY benchmarks/bench_mpm.py --cells ${MPM_CELLS##* } --precision float64 float32 \
           --repeats 3 --min-time $MIN_TIME --sort-every 20 --label gpu-sort20 --out "$OUT/results_mpm_gpu.json" ;;
    euler) stage euler 300 $PY benchmarks/bench_euler.py --sizes $EULER_SIZES --precision float64 float32 --repeats 3 \
           --min-time $MIN_TIME --gpu-bandwidth 4.8e12 --out "$OUT/results_euler_gpu.json" ;;
    slab2d) stage slab2d 400 bash -c "slab_runs cfdmp-32.5us mpm-32.5us" ;;
    slab2d-cache) for round in 1 2; do  # the pair twice with JAX's persistent compilation cache: what it saves
                    stage "slab2d-cache-$round" 300 env JAX_COMPILATION_CACHE_DIR=/tmp/xla_cache \
                      bash -c "slab_runs cfdmp-32.5us mpm-32.5us"
                  done ;;
    slab3d) stage slab3d 300 bash -c slab3d_run ;;
    profile) for task in "mpm $MPM_PROFILE_CELLS" "slab cfdmp-32.5us 1.2e-5" "slab mpm-32.5us 1.2e-5"; do
               stage "profile-$task" 200 env PROFILE_OUT="$OUT/profile_gpu.json" $PY benchmarks/gpu_profile.py $task
             done
             stage "profile-mpm-float32" 200 env BLASTFSI_X64=0 PROFILE_OUT="$OUT/profile_gpu.json" \
               $PY benchmarks/gpu_profile.py mpm $MPM_PROFILE_CELLS ;;
    runprof) for name in cfdmp-32.5us mpm-32.5us; do
               stage "runprof-$name" 300 env PROFILE_OUT="$OUT/profile_run_gpu.json" $PY benchmarks/profile_run.py $name \
                 ${SLAB_END}
             done ;;
    tests) stage tests 240 env XLA_PYTHON_CLIENT_PREALLOCATE=false $PY -m pytest -q -x -n 8 -p no:cacheprovider \
           tests/test_mpm.py tests/test_euler_kernels.py tests/test_cfdmp.py ;;
    *) echo "unknown stage $s" | tee -a "$LOG" ;;
  esac
done
tail -n 60 "$LOG"
