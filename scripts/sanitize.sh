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
# The unit tests of the libraries that read users' files and do the numbers; the end-to-end
# labels (cli, durability, export's Blender and validator runs, python) run their programs
# uninstrumented in the default suite and would take 3x longer here (docs/testing.md).
SANITIZED_LABELS=${SVBTDF_SANITIZED_LABELS:-'^(common|model|session|simulate|calib|fit|process|acquire|report|render|export|fuzz)$'}

bash scripts/install-deps.sh
# RelWithDebInfo's optimisation with line tables only: sanitizer reports name the line, and the
# tests run at a useful speed.
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS=-gline-tables-only \
  -DCMAKE_CXX_COMPILER=clang++-14 -DSVBTDF_SANITIZE=ON -DSVBTDF_FUZZ=ON \
  -DSVBTDF_BUILD_BENCH=OFF -DSVBTDF_PYTHON=OFF >/dev/null
cmake --build "$BUILD_DIR" --parallel "$(nproc)"

# Leaks fail too; halt_on_error makes every report a failure rather than a line in a log.
export ASAN_OPTIONS=${ASAN_OPTIONS:-halt_on_error=1:detect_leaks=1:abort_on_error=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}

echo "== tests under AddressSanitizer and UndefinedBehaviorSanitizer (labels $SANITIZED_LABELS)"
ctest --test-dir "$BUILD_DIR" --output-on-failure --parallel "$(nproc)" --timeout 900 -L "$SANITIZED_LABELS"

echo "== fuzzing every reader for $FUZZ_SECONDS s (seed $FUZZ_SEED)"
python3 scripts/run_fuzzers.py --build "$BUILD_DIR" --seconds "$FUZZ_SECONDS" --seed "$FUZZ_SEED" \
  --jobs "$(nproc)"
