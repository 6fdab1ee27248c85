#!/usr/bin/env bash
# The checked build (docs/testing.md): svbtdf built with Clang,
# AddressSanitizer and UndefinedBehaviorSanitizer; the tests of SANITIZED_LABELS run under them;
# then every libFuzzer harness of tests/fuzz runs for SVBTDF_FUZZ_SECONDS (default 60) on a copy
# of its committed corpus, two at a time. A sanitizer report, a failed test or a fuzz finding
# fails the script; a finding's input is kept in $BUILD_DIR/fuzz-findings/ with the command that
# replays it.
#   scripts/sanitize.sh                          what .ci/run runs
#   SVBTDF_FUZZ_SECONDS=3600 scripts/sanitize.sh  a long fuzzing session (new corpus entries are
#                                                 left in $BUILD_DIR/fuzz-corpus/, not committed)
set -euo pipefail
cd "$(dirname "$0")/.."

BUILD_DIR=${SVBTDF_SANITIZE_BUILD_DIR:-build-sanitize}
FUZZ_SECONDS=${SVBTDF_FUZZ_SECONDS:-60}
FUZZ_SEED=${SVBTDF_FUZZ_SEED:-1}  # fixed, so that a CI run is repeatable; change it to explore
# Within the checked labels, the end-to-end runs of tests/sanitize-skipped.txt (one name a line, why at
# its top) are left out; SVBTDF_SANITIZE_ALL=1 runs them too (about an hour more).
SKIPPED_TESTS=$(grep -v '^#' tests/sanitize-skipped.txt | sed -e 's/[.()+*?^$|]/\\&/g' | paste -sd'|')
EXCLUDE=()
# Only the programs of the checked labels and the fuzzers (tests/CMakeLists.txt); with
# SVBTDF_SANITIZE_ALL=1 everything, the command line included (some skipped tests run it).
TARGETS=(--target svbtdf_checked)
if [ "${SVBTDF_SANITIZE_ALL:-0}" != 1 ]; then
  # ctest names a parameterised test "NAME  # GetParam() = ...": a name ends at a space or the end.
  EXCLUDE=(-E "^($SKIPPED_TESTS)( |\$)")
else
  TARGETS=()
fi

bash scripts/install-deps.sh
# Release's optimisation with line tables only: sanitizer reports name the line, and the tests run
# at a useful speed. (-O1, which AddressSanitizer's documentation suggests, was measured on a clean
# clone: the build took as long and the checked tests 45% longer; docs/testing.md "Measured".)
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS=-gline-tables-only \
  -DCMAKE_CXX_COMPILER=clang++-14 -DSVBTDF_SANITIZE=ON -DSVBTDF_FUZZ=ON -DSVBTDF_PRECOMPILE_HEADERS=ON \
  -DSVBTDF_BUILD_BENCH=OFF -DSVBTDF_PYTHON=OFF >/dev/null
# The labels the checked build runs are tests/CMakeLists.txt's (SVBTDF_CHECKED_LABELS).
SANITIZED_LABELS=${SVBTDF_SANITIZED_LABELS:-$(cat "$BUILD_DIR/checked-labels.txt")}
START=$SECONDS
cmake --build "$BUILD_DIR" --parallel "$(nproc)" "${TARGETS[@]}"
BUILT=$SECONDS

# Leaks fail too; halt_on_error makes every report a failure rather than a line in a log.
export ASAN_OPTIONS=${ASAN_OPTIONS:-halt_on_error=1:detect_leaks=1:abort_on_error=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}

# A test added since tests/sanitize-skipped.txt was last drawn up, which took 1 s or more in this
# machine's release suite (its ctest cost data, when scripts/test.sh ran first), is named here: each
# such test costs 10-30x that under the sanitizers and is how the budget was lost before.
RELEASE_COSTS=${SVBTDF_BUILD_DIR:-build}/Testing/Temporary/CTestCostData.txt
if [ -f "$RELEASE_COSTS" ]; then
  ctest --test-dir "$BUILD_DIR" -N -L "$SANITIZED_LABELS" "${EXCLUDE[@]}" | sed -n 's/^ *Test *#[0-9]*: //p' |
    awk 'NR == FNR { name = $0; sub(/ +[0-9]+ +[0-9.e+-]+$/, "", name); if ($NF >= 1.0) slow[name] = $NF; next }
         ($0 in slow) { printf "warning: %s took %.1f s in the release suite and is sanitized; list it in tests/sanitize-skipped.txt\n", $0, slow[$0] }' \
      "$RELEASE_COSTS" -
fi

echo "== tests under AddressSanitizer and UndefinedBehaviorSanitizer (labels $SANITIZED_LABELS)"
ctest --test-dir "$BUILD_DIR" --output-on-failure --parallel "$(nproc)" --timeout 900 -L "$SANITIZED_LABELS" \
  "${EXCLUDE[@]}"

TESTED=$SECONDS
echo "== fuzzing every reader for $FUZZ_SECONDS s (seed $FUZZ_SEED)"
python3 scripts/run_fuzzers.py --build "$BUILD_DIR" --seconds "$FUZZ_SECONDS" --seed "$FUZZ_SEED" \
  --jobs "$(nproc)"
# What the checked build adds to CI, in the log (docs/testing.md "Measured" quotes it).
echo "== checked build: build $((BUILT - START)) s, tests $((TESTED - BUILT)) s, fuzzing $((SECONDS - TESTED)) s," \
  "total $((SECONDS - START)) s"
