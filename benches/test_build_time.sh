#!/usr/bin/env bash
# How long the test suite takes to build: the figures of docs/performance.md ("Building the
# tests"). Measures, in a target directory of its own (so a developer's target/ is untouched):
#   1. cold:        dependencies already built, droidctl's library, binary and every test
#                   binary built from scratch (`cargo clean -p droidctl`, then
#                   `cargo test --no-run`);
#   2. incremental: `touch` one file in src/ui, then `cargo test --no-run` again.
# Each is timed by /usr/bin/time (wall, user and system seconds); the load average before each
# is printed, since on a shared machine CPU time (user+sys) is the fair comparison and wall
# time is not. Run it in two checkouts (before and after a change) to compare.
# Usage: bash benches/test_build_time.sh [TARGET_DIR] [RUNS]
#   TARGET_DIR: default target/test-build-time; RUNS: cold+incremental pairs, default 1.
#   WARM=0 skips the untimed first build (when TARGET_DIR already holds the dependencies).
set -euo pipefail
cd "$(dirname "$0")/.."
target=${1:-target/test-build-time}
runs=${2:-1}
export CARGO_TARGET_DIR=$target
touched=src/ui/status.rs

log=$(mktemp)
trap 'rm -f "$log"' EXIT

timed() {
  local label=$1
  shift
  echo "load average before $label: $(cut -d' ' -f1-3 /proc/loadavg)"
  if ! /usr/bin/time -o "$log" -f "$label: wall %e s, user %U s, sys %S s, max RSS %M KiB" \
    "$@" >/dev/null; then
    echo "$label: the build failed" >&2
    exit 1
  fi
  cat "$log"
}

# Dependencies (and droidctl once) built first, untimed: what is measured is droidctl's own.
if [ "${WARM:-1}" != 0 ]; then
  cargo test --no-run -q >/dev/null
fi
for _ in $(seq "$runs"); do
  cargo clean -q -p droidctl
  timed cold cargo test --no-run -q
  touch "$touched"
  timed incremental cargo test --no-run -q
done
echo "test binaries built: $(cargo test --no-run --message-format=json 2>/dev/null \
  | grep '"reason":"compiler-artifact"' | grep -c '"profile":{[^}]*"test":true')"
