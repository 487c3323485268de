#!/usr/bin/env bash
# Idle cost of the running app: `droidctl --sim` (sensor streaming on, 10 Hz control loop,
# nobody touching the keys) in a 160×48 tmux window, sampled from /proc.
# Usage: bash benches/idle.sh [SECONDS] [stream50|scope]   (needs tmux; builds the release binary)
# `stream50`: the droid streams attitude at 50/s; `scope`: the same with the scope on screen
# (key g).
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${1:-30}
mode=${2:-}
cargo build --release -q
bin=${CARGO_TARGET_DIR:-$PWD/target}/release/droidctl
tmp=$(mktemp -d)
trap 'tmux kill-session -t droidctl-idle 2>/dev/null || true; rm -rf "$tmp"' EXIT
if [ "$mode" = scope ] || [ "$mode" = stream50 ]; then
  printf '[streaming]\nrate_hz = 50\nsensors = ["attitude"]\n' > "$tmp/config.toml"
fi
tmux new-session -d -s droidctl-idle -x 160 -y 48 \
  "DROIDCTL_LOG_FILE=$tmp/log DROIDCTL_CONFIG=$tmp/config.toml $bin --sim"
sleep 5   # connect, stand up, start streaming
if [ "$mode" = scope ]; then
  tmux send-keys -t droidctl-idle g
  sleep 1
fi
pid=$(pgrep -f "^$bin --sim" | head -n1)
hz=$(getconf CLK_TCK)
ticks() { awk '{print $14 + $15}' "/proc/$pid/stat"; }
t0=$(ticks); s0=$(date +%s.%N)
sleep "$secs"
t1=$(ticks); s1=$(date +%s.%N)
rss=$(awk '/VmRSS/ {print $2}' "/proc/$pid/status")
hwm=$(awk '/VmHWM/ {print $2}' "/proc/$pid/status")
cpu=$(echo "($t1 - $t0) / $hz / ($s1 - $s0) * 100" | bc -l)
printf 'idle over %ss: CPU %.2f %% of one core, RSS %.1f MiB (peak %.1f MiB)\n' \
  "$secs" "$cpu" "$(echo "$rss/1024" | bc -l)" "$(echo "$hwm/1024" | bc -l)"
tmux send-keys -t droidctl-idle q
