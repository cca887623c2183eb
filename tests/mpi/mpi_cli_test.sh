#!/bin/sh
# The command line under mpirun, 2 ranks on this machine (tests/CMakeLists.txt runs it).
#   mpi_cli_test.sh MPIEXEC CAUSTICA WORKDIR identical INTEGRATOR [SPP]
#       fixed --spp (default 5): 1 process (no mpirun) and 2 ranks write byte-identical EXR files
#   mpi_cli_test.sh MPIEXEC CAUSTICA WORKDIR time [INTEGRATOR]
#       --time with checkpoints (default pt): one set of files (exr, png, json), iterations
#       summed over ranks
#   mpi_cli_test.sh MPIEXEC CAUSTICA WORKDIR rank-fails
#       rank 1 gets a scene file that does not exist: every rank stops, exit code 2, one message
set -u
mpiexec=$1 caustica=$2 work=$3 mode=$4
rm -rf "$work" && mkdir -p "$work" || exit 1
cd "$work" || exit 1
fail() { echo "FAIL: $*"; exit 1; }
# -q: no Open MPI banner when a rank exits non-zero; the job's own message is the one we check.
mpi() { timeout 120 "$mpiexec" -q --oversubscribe "$@"; }
common="--resolution 40x30 --threads 1 --quiet"

case $mode in
identical)
  integrator=$5 spp=${6:-5}
  "$caustica" render --integrator "$integrator" --spp "$spp" --seed 3 $common --outfile one.exr ||
    fail "one process"
  mpi -np 2 "$caustica" render --integrator "$integrator" --spp "$spp" --seed 3 $common \
    --outfile two.exr || fail "2 ranks"
  grep -q '"ranks": 2' two.json || fail "two.json does not say 2 ranks"
  grep -q "\"iterations\": $spp" two.json || fail "two.json does not count $spp iterations"
  cmp one.exr two.exr || fail "$integrator: 1 process and 2 ranks differ"
  # A different seed must change the file, or the comparison above proves nothing.
  "$caustica" render --integrator "$integrator" --spp "$spp" --seed 4 $common --outfile other.exr ||
    fail "other seed"
  cmp -s one.exr other.exr && fail "$integrator: seeds 3 and 4 gave the same file"
  ;;
time)
  mkdir out || exit 1
  mpi -np 2 "$caustica" render --integrator "${5:-pt}" --time 3 --checkpoint 1 $common \
    --outfile out/img || fail "timed run"
  files=$(ls -A out | tr '\n' ' ')
  [ "$files" = "img.exr img.json img.png " ] || fail "expected one set of files, got: $files"
  grep -q '"ranks": 2' out/img.json || fail "img.json does not say 2 ranks"
  grep -q '"checkpoint"' out/img.json && fail "the final JSON is a checkpoint's"
  iterations=$(sed -n 's/.*"iterations": \([0-9]*\).*/\1/p' out/img.json)
  [ "${iterations:-0}" -ge 2 ] || fail "iterations over ranks: '$iterations'"
  ;;
rank-fails)
  start=$(date +%s)
  mpi -np 1 "$caustica" render --spp 2 $common --outfile ok : \
    -np 1 "$caustica" render "$work/missing.pbrt" --spp 2 $common --outfile ok 2>err.txt
  rc=$?
  seconds=$(($(date +%s) - start))
  cat err.txt
  [ $rc -eq 2 ] || fail "exit code $rc, expected 2"
  [ "$seconds" -le 60 ] || fail "took $seconds s"
  [ "$(grep -c . err.txt)" -eq 1 ] || fail "expected exactly one line on stderr"
  grep -q "^caustica: error: rank 1 of 2: .*missing.pbrt" err.txt || fail "message does not name rank 1 and the file"
  ls ok.* >/dev/null 2>&1 && fail "files were written"
  ;;
*) fail "unknown mode $mode" ;;
esac
echo PASS
