#!/usr/bin/env bash
# Synthesis cost of the simulator presets: wall time, peak resident memory and disk size of
# `neraf synth --preset P` (each preset's default layout), with the machine, date and load.
#   bench/synth_presets.sh OUT.json [THREADS] [PRESET ...]
# Default presets: the ones added for issues 13 and 14. The datasets are written to a temporary
# folder and deleted after measuring (the largest is ~4 GB).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: bench/synth_presets.sh OUT.json [THREADS] [PRESET ...]}
threads=${2:-2}
shift $(($# >= 2 ? 2 : $#))
presets=("$@")
[ ${#presets[@]} -gt 0 ] ||
  presets=(occluded furnished_room empty_room small_dead large_live apartment raf_large)
neraf=build/neraf
work=$(mktemp -d "${TMPDIR:-/tmp}/neraf_synth_bench.XXXXXX")
trap 'rm -rf "$work"' EXIT

commit=$(git rev-parse --short HEAD)  # the build measured is of the working tree at this commit
rows=()
for p in "${presets[@]}"; do
  load_before=$(cut -d' ' -f1-3 /proc/loadavg)
  dry=$("$neraf" synth --preset "$p" --dry-run | tr '\n' ' ' | sed 's/"/\\"/g')
  /usr/bin/time -f "%e %M" -o "$work/time" "$neraf" synth --preset "$p" --out "$work/ds" --quiet \
    --threads "$threads" >"$work/summary" 2>&1
  read -r wall rss_kb <"$work/time"
  bytes=$(du -sb "$work/ds" | cut -f1)
  load_after=$(cut -d' ' -f1-3 /proc/loadavg)
  info=$(cat "$work/ds/synth_info.json")
  summary=$(tr '\n' ' ' <"$work/summary" | sed 's/"/\\"/g')
  rows+=("{\"preset\": \"$p\", \"command\": \"neraf synth --preset $p --out DIR --quiet --threads $threads\", \"wall_s\": $wall, \"peak_rss_kb\": $rss_kb, \"disk_bytes\": $bytes, \"load_before\": \"$load_before\", \"load_after\": \"$load_after\", \"dry_run\": \"$dry\", \"summary\": \"$summary\", \"synth_info\": $info}")
  rm -rf "$work/ds"
  echo "$p: ${wall} s, peak RSS ${rss_kb} kB, ${bytes} bytes" >&2
done

{
  echo "{\"generator\": \"bench/synth_presets.sh\", \"date\": \"$(date -u +%FT%TZ)\","
  echo " \"machine\": \"$(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cores, $(free -g | awk '/Mem:/{print $2}') GB\","
  echo " \"commit\": \"$commit\", \"threads\": $threads,"
  echo " \"note\": \"load_before/after: /proc/loadavg (1, 5, 15 min); other engineers share the 2 cores\","
  echo " \"presets\": ["
  for i in "${!rows[@]}"; do
    sep=$([ "$i" -lt $((${#rows[@]} - 1)) ] && echo "," || echo "")
    echo "  ${rows[$i]}$sep"
  done
  echo "]}"
} >"$out"
python3 -m json.tool "$out" >/dev/null
echo "wrote $out" >&2
