#!/usr/bin/env bash
# Idle cost of the running app: `droidctl --sim MODEL` (sensor streaming on, 10 Hz control loop,
# nobody touching the keys) in a 160×48 tmux window, sampled from /proc.
# Usage: bash benches/idle.sh [SECONDS] [MODEL] [stream50|scope]   (MODEL: r2d2 (default),
# robi, bb8 …; `stream50`: the droid streams attitude at 50/s; `scope`: the same with the scope
# on screen, key g). Needs tmux; builds the release binary first, in $CARGO_TARGET_DIR when
# set, unless IDLE_BIN names one to measure (e.g. an older build to compare with).
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${1:-30}
model=${2:-r2d2}
mode=${3:-}
if [ -n "${IDLE_BIN:-}" ]; then
  bin=$IDLE_BIN
else
  cargo build --release -q
  bin=${CARGO_TARGET_DIR:-$PWD/target}/release/droidctl
fi
tmp=$(mktemp -d)
session=droidctl-idle-$$
trap 'tmux kill-session -t "$session" 2>/dev/null || true; rm -rf "$tmp"' EXIT
if [ "$mode" = scope ] || [ "$mode" = stream50 ]; then
  printf '[streaming]\nrate_hz = 50\nsensors = ["attitude"]\n' > "$tmp/config.toml"
fi
tmux new-session -d -s "$session" -x 160 -y 48 \
  "DROIDCTL_LOG_FILE=$tmp/log DROIDCTL_CONFIG=$tmp/config.toml $bin --sim $model"
sleep 5   # connect, stand up, start streaming
if [ "$mode" = scope ]; then
  tmux send-keys -t "$session" g
  sleep 1
fi
pid=$(pgrep -f "^$bin --sim $model\$" | head -n1)
hz=$(getconf CLK_TCK)
ticks() { awk '{print $14 + $15}' "/proc/$pid/stat"; }
t0=$(ticks); s0=$(date +%s.%N)
sleep "$secs"
t1=$(ticks); s1=$(date +%s.%N)
rss=$(awk '/VmRSS/ {print $2}' "/proc/$pid/status")
hwm=$(awk '/VmHWM/ {print $2}' "/proc/$pid/status")
cpu=$(echo "($t1 - $t0) / $hz / ($s1 - $s0) * 100" | bc -l)
printf '%s idle over %ss: CPU %.2f %% of one core, RSS %.1f MiB (peak %.1f MiB)\n' \
  "$model" "$secs" "$cpu" "$(echo "$rss/1024" | bc -l)" "$(echo "$hwm/1024" | bc -l)"
tmux send-keys -t "$session" q
