#!/usr/bin/env bash
# On the GPU machine (device tool), from the repository root, carrying .devdeps-cuda
# (or .devdeps) and devdata/ (t265/robot and synthetic/ copied from ../shared/data):
# build for sm_90, run every test, benchmark, profile the primal-dual kernel, evaluate
# accuracy, and run compute-sanitizer. Logs go to $OUT.
set -uo pipefail
OUT=${OUT:-out}; mkdir -p "$OUT"
DEPS=${DEPS:-.devdeps-cuda}
source "$DEPS/env.sh"
B=build-gpu
step() { echo; echo "=== $*"; }
{
  nvidia-smi --query-gpu=name,driver_version,clocks.max.memory,memory.total --format=csv
  step build
  cmake -S . -B $B -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CUDA_ARCHITECTURES=90 >/dev/null &&
    cmake --build $B 2>&1 | grep -E "warning|error|FAILED" ; echo "build rc=${PIPESTATUS[0]}"
} 2>&1 | tee "$OUT/build.log"
{
  step ctest
  timeout 240 ctest --test-dir $B -j8 --output-on-failure 2>&1 | tail -40
  step test_backends verbose
  timeout 120 $B/tests/test_backends -s 2>&1 | grep -E "MESSAGE|test cases|ERROR"
  step test_cuda_device verbose
  timeout 60 $B/tests/test_cuda_device -s 2>&1 | grep -E "MESSAGE|test cases|ERROR"
} 2>&1 | tee "$OUT/tests.log"
CB=$B/backend_cuda/curvestereo_cuda_bench
T265="--calib devdata/t265/robot/camchain.yaml devdata/t265/robot/left.png devdata/t265/robot/right.png"
# The bench reads its pair from files: `pair NAME SYNTH-OPTIONS...` renders one once (into
# $OUT/pairs/NAME) and prints the bench's --calib arguments for it.
pair() {
  local dir="$OUT/pairs/$1"
  shift
  [ -d "$dir" ] || $B/tools/curvestereo synth -o "$dir" --samples 1 --quiet "$@" >/dev/null
  echo "--calib $dir/camchain.yaml $dir/left.png $dir/right.png"
}
T265LENS="--calib devdata/t265/robot/camchain.yaml"  # synthetic scenes through the T265's lenses, 848x800
{
  step "T265 848x800 N=5 (realtime: 5 levels x2, K=10)"; $CB $T265 --preset realtime --runs 50
  step "T265 848x800 N=20"; $CB $T265 --preset realtime --warps 20 --runs 50
  step "synthetic 848x800 N=5"; $CB $(pair t265-848 $T265LENS) --preset realtime --runs 50
  step "synthetic 848x800 N=20"; $CB $(pair t265-848 $T265LENS) --preset realtime --warps 20 --runs 50
  step "800x800 paper config"; $CB $(pair square-800 --size 800) --preset realtime --runs 50
  step "424x400 N=20"; $CB $(pair t265-424 $T265LENS --size 424) --preset realtime --warps 20 --runs 50
  for s in 400 1600; do
    step "scaling ${s}x${s} paper config"; $CB $(pair square-$s --size $s) --preset realtime --runs 50
  done
  step "curvestereo bench --backend cuda (host API, T265, N=5)"
  $B/tools/curvestereo bench --backend cuda $T265 --preset realtime --runs 50 2>&1 | grep -v "benchmark"
  step "curvestereo bench --backend cuda (host API, 848x800, N=20)"
  $B/tools/curvestereo bench --backend cuda --size 848x800 --preset realtime --warps 20 --runs 50 2>&1 | grep -v "benchmark"
} 2>&1 | tee "$OUT/bench.log"
{
  step "eval synthetic, default preset, cuda"
  timeout 150 $B/tools/curvestereo eval devdata/synthetic/*/ --backend cuda --csv "$OUT/eval.csv" --md "$OUT/eval.md" 2>&1 | tail -20
} 2>&1 | tee "$OUT/eval.log"
{
  step "ncu primal-dual (848x800 level 0)"
  timeout 120 ncu --kernel-name regex:primalDual --launch-skip 210 --launch-count 2 \
    --section SpeedOfLight --section MemoryWorkloadAnalysis --section LaunchStats --section Occupancy \
    --metrics dram__bytes_read.sum,dram__bytes_write.sum,lts__t_bytes.sum,gpu__time_duration.sum \
    $CB $(pair t265-848 $T265LENS) --preset realtime --runs 1 2>&1 | grep -vE "^==PROF==" | tail -120
} 2>&1 | tee "$OUT/ncu.log"
{
  step "compute-sanitizer memcheck test_backends"
  timeout 110 compute-sanitizer --tool memcheck --error-exitcode 9 $B/tests/test_backends 2>&1 | tail -8
  step "compute-sanitizer racecheck test_backends"
  timeout 110 compute-sanitizer --tool racecheck --error-exitcode 9 $B/tests/test_backends 2>&1 | tail -8
  step "compute-sanitizer memcheck test_cuda_device"
  timeout 45 compute-sanitizer --tool memcheck --error-exitcode 9 $B/tests/test_cuda_device 2>&1 | tail -6
  step "compute-sanitizer synccheck/initcheck test_cuda_device"
  timeout 45 compute-sanitizer --tool initcheck --error-exitcode 9 $B/tests/test_cuda_device 2>&1 | tail -6
} 2>&1 | tee "$OUT/sanitizer.log"
