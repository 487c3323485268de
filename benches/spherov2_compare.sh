#!/usr/bin/env bash
# droidctl's v2 decoder against spherov2.py's, on the same bytes, in the same run.
#
# The stream is the codec benchmark's mixed one (benches/codec.rs: sensor streaming, drive
# commands, responses, collisions, escaped LED values). Prints:
#   - droidctl's decoder (Decoder::feed_with, criterion's median throughput);
#   - the whole `droidctl packet decode --file FILE --summary` on a large file (wall time,
#     peak RSS: memory stays flat whatever the size);
#   - spherov2.py's own parser (spherov2/controls/v2.py, Packet.Collector.add, which calls
#     Packet.parse_response per packet) on the same stream, installed with pip in a venv;
#   - the ratio.
#   - the case a user meets: a mixed stream as spherov2.py's own `Packet.build` makes it
#     (benches/spherov2_mixed.py), `packet decode --file - --json` into a file, against
#     spherov2's Collector fed in 20-byte chunks (packets/s, and the ratio);
# The Python half is skipped with a message when spherov2 cannot be installed.
#
# Usage: bash benches/spherov2_compare.sh [CLI_FILE_MB]   (default 256)
set -euo pipefail
cd "$(dirname "$0")/.."
mb=${1:-256}
work=target/spherov2-compare
mkdir -p "$work"
stream=$work/stream.bin

echo "building (release) and measuring droidctl's decoder with criterion..."
cargo build --release -q
bin=${CARGO_TARGET_DIR:-target}/release/droidctl
sensors=$work/sensors.bin
bench_out=$(DROIDCTL_CODEC_STREAM="$PWD/$stream" DROIDCTL_SENSOR_STREAM="$PWD/$sensors" \
  cargo bench -q --bench codec -- \
  --warm-up-time 1 --measurement-time 3 'v2/decode_borrowed$' 2>&1)
# criterion: "thrpt:  [low MiB/s  median MiB/s  high MiB/s]"
rust_mibs=$(echo "$bench_out" | awk '/thrpt:/ {gsub(/\[/, ""); print $4; exit}')
rust_unit=$(echo "$bench_out" | awk '/thrpt:/ {print $5; exit}')
case $rust_unit in
  GiB/s) rust_mbs=$(echo "$rust_mibs * 1073.741824" | bc -l) ;;
  MiB/s) rust_mbs=$(echo "$rust_mibs * 1.048576" | bc -l) ;;
  *) echo "cannot read criterion's throughput:"; echo "$bench_out"; exit 1 ;;
esac
bytes=$(stat -c %s "$stream")

# The CLI on a large file made of the same stream.
big=$work/big.bin
if [ ! -f "$big" ] || [ "$(stat -c %s "$big")" -lt $((mb * 1000000)) ]; then
  : > "$big"
  reps=$((mb * 1000000 / bytes + 1))
  for _ in $(seq "$reps"); do cat "$stream"; done > "$big"
fi
big_bytes=$(stat -c %s "$big")
cat "$big" > /dev/null   # warm the page cache
timing=$( { /usr/bin/time -f '%e %M' "$bin" packet decode --file "$big" --summary > "$work/cli.out"; } 2>&1 )
secs=$(echo "$timing" | tail -n1 | awk '{print $1}')
rss_kb=$(echo "$timing" | tail -n1 | awk '{print $2}')
cli_mbs=$(echo "$big_bytes / $secs / 1000000" | bc -l)

echo "stream: $bytes bytes (benches/codec.rs); the CLI on the large file: $(cat "$work/cli.out")"
printf 'droidctl  Decoder::feed_with (criterion median):             %8.1f MB/s\n' "$rust_mbs"
printf 'droidctl  packet decode --file --summary, %4d MB file:        %8.1f MB/s, peak RSS %.1f MiB\n' \
  "$((big_bytes / 1000000))" "$cli_mbs" "$(echo "$rss_kb / 1024" | bc -l)"

# spherov2.py in a venv.
venv=$work/venv
py=${PYTHON:-python3}
if [ ! -x "$venv/bin/python" ]; then
  "$py" -m venv "$venv" > /dev/null 2>&1 || true
fi
if [ -x "$venv/bin/python" ] && "$venv/bin/python" -c 'import spherov2' 2> /dev/null \
   || { [ -x "$venv/bin/pip" ] && "$venv/bin/pip" install -q spherov2 > "$work/pip.log" 2>&1; }; then
  sv2_version=$("$venv/bin/python" -c 'import importlib.metadata as m; print(m.version("spherov2"))')
  pyver=$("$venv/bin/python" -c 'import platform; print(platform.python_version())')
  read -r py_mbs py_packets py_bytes py_secs < <("$venv/bin/python" - "$stream" <<'EOF'
import sys, time
from spherov2.controls.v2 import Packet
data = open(sys.argv[1], 'rb').read()
reps = max(1, int(4e6 // len(data)))
count = [0]
def counted(packet):
    count[0] += 1
collector = Packet.Collector(counted)
start = time.perf_counter()
for _ in range(reps):
    collector.add(data)
took = time.perf_counter() - start
print(f"{reps * len(data) / took / 1e6:.4f} {count[0] // reps} {reps * len(data)} {took:.3f}")
EOF
)
  # Full-mask sensor notifications only (issue 27 point 10): `packet decode --json` on a
  # large file of them, packets/s, against spherov2's bare parser on the same stream.
  read -r mask ext < "$sensors.masks"
  sbig=$work/sensors-big.bin
  sreps=$((64000000 / $(stat -c %s "$sensors") + 1))
  for _ in $(seq "$sreps"); do cat "$sensors"; done > "$sbig"
  cat "$sbig" > /dev/null
  spackets=$("$bin" packet decode --file "$sbig" --json --sensor-mask "$mask" --ext-mask "$ext" | wc -l)
  stiming=$( { /usr/bin/time -f '%e %M' "$bin" packet decode --file "$sbig" --json --sensor-mask "$mask" --ext-mask "$ext" > /dev/null; } 2>&1 )
  ssecs=$(echo "$stiming" | tail -n1 | awk '{print $1}')
  srss=$(echo "$stiming" | tail -n1 | awk '{print $2}')
  read -r py_spps < <("$venv/bin/python" - "$sensors" <<'EOF'
import sys, time
from spherov2.controls.v2 import Packet
data = open(sys.argv[1], 'rb').read()
reps = max(1, int(4e6 // len(data)))
count = [0]
def counted(packet):
    count[0] += 1
collector = Packet.Collector(counted)
start = time.perf_counter()
for _ in range(reps):
    collector.add(data)
took = time.perf_counter() - start
print(f"{count[0] / took:.0f}")
EOF
)
  rust_spps=$(echo "$spackets / $ssecs" | bc -l)
  printf 'full-mask sensor notifications: droidctl packet decode --json, %d packets: %8.0f packets/s (peak RSS %.1f MiB)\n' \
    "$spackets" "$rust_spps" "$(echo "$srss / 1024" | bc -l)"
  printf 'full-mask sensor notifications: spherov2.py Packet.Collector:              %8.0f packets/s\n' "$py_spps"
  printf 'ratio (packet decode --json / spherov2 parser) = %.1fx\n' "$(echo "$rust_spps / $py_spps" | bc -l)"
  printf 'spherov2.py %s Packet.Collector (Python %s, %s MB):   %8.3f MB/s (%s packets per stream)\n' \
    "$sv2_version" "$pyver" "$((py_bytes / 1000000))" "$py_mbs" "$py_packets"
  printf 'ratio: droidctl decoder / spherov2.py = %.0f×; droidctl CLI / spherov2.py = %.0f×\n' \
    "$(echo "$rust_mbs / $py_mbs" | bc -l)" "$(echo "$cli_mbs / $py_mbs" | bc -l)"

  # The case a user meets (issue 42 point 6): a mixed stream as spherov2's own Packet.build
  # makes it (half notifications of 17 floats, no masks given; drive commands, responses,
  # LED commands that need escapes), `packet decode --file - --json` from stdin into a file,
  # against spherov2's Collector fed in 20-byte BLE-sized chunks. Python's packets/s do not
  # depend on the stream's length: it decodes a tenth of droidctl's.
  mixed=$work/mixed.bin
  mixed_py=$work/mixed-py.bin
  mixed_n=${MIXED_PACKETS:-200000}
  "$venv/bin/python" benches/spherov2_mixed.py write "$mixed" "$mixed_n"
  "$venv/bin/python" benches/spherov2_mixed.py write "$mixed_py" $((mixed_n / 10))
  cat "$mixed" > /dev/null
  mtiming=$( { /usr/bin/time -f '%e %M' "$bin" packet decode --file - --json < "$mixed" > "$work/mixed.json"; } 2>&1 )
  msecs=$(echo "$mtiming" | tail -n1 | awk '{print $1}')
  mlines=$(wc -l < "$work/mixed.json")
  read -r _ _ py_mpps < <("$venv/bin/python" benches/spherov2_mixed.py time "$mixed_py")
  rust_mpps=$(echo "$mlines / $msecs" | bc -l)
  printf 'mixed stream (spherov2 Packet.build), droidctl packet decode --file - --json > file, %d packets: %8.0f packets/s\n' \
    "$mlines" "$rust_mpps"
  printf 'mixed stream, spherov2.py Packet.Collector in 20-byte chunks:                                 %8.0f packets/s\n' "$py_mpps"
  printf 'ratio (packet decode --json / spherov2 Collector, 20-byte chunks) = %.1fx\n' \
    "$(echo "$rust_mpps / $py_mpps" | bc -l)"
else
  echo "spherov2.py: skipped (cannot create a venv or pip install spherov2; see $work/pip.log)"
fi
