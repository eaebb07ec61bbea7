#!/usr/bin/env bash
# The offline fuzz run of issue 18: the fuzz tests (tests/e2e/test_fuzz.py and
# tests/e2e/test_fuzz_hostile.py) with fresh random seeds, in chunks, in LANES
# parallel lanes, pinned low with nice; each chunk's tally line (inputs and
# exit codes) go to OUT/lane-*.txt, each chunk's whole output (failures)
# to OUT/chunk-LANE-N.txt. Sum them with
#   grep -h "inputs;" OUT/lane-*.txt
# Usage: benchmarks/fuzz_offline.sh OUT [CHUNKS] [EXAMPLES_PER_TEST] [LANES]
set -u
out=${1:?usage: fuzz_offline.sh OUT [CHUNKS] [EXAMPLES] [LANES]}
chunks=${2:-10}
examples=${3:-2000}
lanes=${4:-2}
mkdir -p "$out"
cd "$(dirname "$0")/.."
lane() {
    for chunk in $(seq 1 "$chunks"); do
        echo "== lane $1 chunk $chunk $(date -u +%H:%M:%S)"
        HTN_FUZZ_EXAMPLES=$examples HTN_FUZZ_RANDOM=1 nice -n 15 \
            python -m pytest -q -s -p no:cacheprovider -m slow \
            tests/e2e/test_fuzz.py tests/e2e/test_fuzz_hostile.py > "$out/chunk-$1-$chunk.txt" 2>&1
        grep -E "inputs;|passed|failed" "$out/chunk-$1-$chunk.txt"
    done
}
for n in $(seq 1 "$lanes"); do
    lane "$n" > "$out/lane-$n.txt" 2>&1 &
done
wait
