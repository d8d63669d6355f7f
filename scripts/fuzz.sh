#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/, cmake/fuzz.cmake) into build-fuzz/ with clang and runs each
# for SECONDS (default 60) on a fresh copy of its seed corpus (fuzz/corpus/<target>), one after the
# other. Prints executions, coverage and the outcome per target; exits 1 when any target found a
# crash, sanitizer report, leak, timeout or out-of-memory (reproducer and log under
# build-fuzz/findings/ and build-fuzz/logs/; fuzz/README.md says how to replay one).
#   scripts/fuzz.sh              every target, 60 s each
#   scripts/fuzz.sh 30           30 s each
#   scripts/fuzz.sh 30 npy c_api only these targets (names as in fuzz/fuzz_<name>.cpp)
# Environment: CC/CXX pick the compiler (default: the newest clang-16/15/14, else clang),
# NERAF_FUZZ_JOBS the build's parallelism (default 2, as scripts/build.sh), NERAF_FUZZ_PARALLEL
# how many targets run at once (default 1; on a many-core machine, e.g. 16, every target gets a
# core), NERAF_FUZZ_PREBUILT=1 runs the targets already in build-fuzz/fuzz without building (a
# machine without clang running another's build).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
[ $# -gt 0 ] && shift
if ! [[ "$seconds" =~ ^[0-9]+$ ]] || [ "$seconds" -eq 0 ]; then
  echo "fuzz: SECONDS must be a positive whole number, not '$seconds'" >&2
  exit 2
fi
build="build-fuzz"

if [ "${NERAF_FUZZ_PREBUILT:-0}" != 1 ]; then
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  apt_install() {
    echo "fuzz: installing $*"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "$@"
  }

  # ---- compiler: clang with libFuzzer's and the sanitizers' runtimes, and its OpenMP --------------
  pick_clang() {
    if [ -n "${CXX:-}" ]; then
      echo "${CC:-${CXX/clang++/clang}} $CXX"
      return
    fi
    for v in 16 15 14; do
      if command -v "clang++-$v" >/dev/null 2>&1; then
        echo "clang-$v clang++-$v"
        return
      fi
    done
    command -v clang++ >/dev/null 2>&1 && echo "clang clang++"
  }
  # Whether $1 links a libFuzzer target with ASan/UBSan and OpenMP (the runtimes are separate Debian
  # packages from the compiler).
  can_fuzz() {
    local probe
    probe=$(mktemp -d)
    printf '%s\n' '#include <cstddef>' '#include <cstdint>' \
      'extern "C" int LLVMFuzzerTestOneInput(const uint8_t*, size_t) { return 0; }' >"$probe/p.cpp"
    "$1" -fsanitize=fuzzer,address,undefined -fopenmp "$probe/p.cpp" -o "$probe/p" >/dev/null 2>&1
    local ok=$?
    rm -rf "$probe"
    return $ok
  }
  read -r cc cxx <<<"$(pick_clang || true)"
  if [ -z "${cxx:-}" ]; then
    apt_install clang libclang-rt-dev libomp-dev  # Debian 12: clang 14
    read -r cc cxx <<<"$(pick_clang)"
  fi
  if ! can_fuzz "$cxx"; then
    ver=$("$cxx" -dumpversion | cut -d. -f1)
    apt_install "libclang-rt-$ver-dev" "libomp-$ver-dev"
    can_fuzz "$cxx" || { echo "fuzz: $cxx cannot link a libFuzzer target" >&2; exit 2; }
  fi

  # ---- build -------------------------------------------------------------------------------------
  generator=()
  command -v ninja >/dev/null 2>&1 && generator=(-G Ninja)
  [ -f "$build/CMakeCache.txt" ] || generator_args=("${generator[@]}")
  cmake -S . -B "$build" "${generator_args[@]+"${generator_args[@]}"}" -DNERAF_FUZZ=ON \
    -DNERAF_WITH_TORCH=OFF -DNERAF_TESTS=OFF -DNERAF_BENCH=OFF -DNERAF_NATIVE=OFF \
    -DCMAKE_UNITY_BUILD=ON -DCMAKE_UNITY_BUILD_BATCH_SIZE=8 \
    -DCMAKE_BUILD_TYPE=Debug -DCMAKE_C_COMPILER="$cc" -DCMAKE_CXX_COMPILER="$cxx" >/dev/null
  cmake --build "$build" --target neraf_fuzz -j "${NERAF_FUZZ_JOBS:-2}"
fi

# ---- run ---------------------------------------------------------------------------------------
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  for src in fuzz/fuzz_*.cpp; do
    name=$(basename "$src" .cpp)
    targets+=("${name#fuzz_}")
  done
fi
# The dictionary of each target (several share one).
dict_of() {
  case "$1" in
    trajectory_file) echo fuzz/trajectory.dict ;;
    c_api) echo fuzz/model_payload.dict ;;
    json_file) echo fuzz/json.dict ;;
    *) [ -f "fuzz/$1.dict" ] && echo "fuzz/$1.dict" ;;
  esac
}
# The targets that read files write each input to a temporary file: on a RAM disk they run an
# order of magnitude faster than on most disks.
if [ -z "${TMPDIR:-}" ] && [ -d /dev/shm ] && [ -w /dev/shm ]; then export TMPDIR=/dev/shm; fi
export LSAN_OPTIONS="suppressions=$PWD/fuzz/lsan.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
export UBSAN_OPTIONS="print_stacktrace=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"

mkdir -p "$build/logs"
# One target: fuzzes it and writes its summary line to $build/logs/<target>.summary; fails when it
# found something.
run_target() {
  local t=$1
  local exe="$build/fuzz/fuzz_$t"
  local corpus="$build/corpus/$t"
  local findings="$build/findings/$t"
  local log="$build/logs/$t.log"
  rm -rf "$corpus" "$findings"
  mkdir -p "$corpus" "$findings"
  cp -r "fuzz/corpus/$t/." "$corpus/"
  local args=(-max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1
              -artifact_prefix="$findings/")
  local dict
  dict=$(dict_of "$t" || true)
  [ -n "$dict" ] && args+=(-dict="$dict")
  echo "fuzz: $t for ${seconds}s"
  local rc=0
  # The outer limit only catches a fuzzer that ignores -max_total_time (a hang outside an input).
  timeout --kill-after=10 $((seconds + 120)) "$exe" "${args[@]}" "$corpus" >"$log" 2>&1 || rc=$?
  local execs cov ft units artifacts result=ok kind
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  cov=$(grep -o 'cov: [0-9]* ft: [0-9]*' "$log" | tail -1 | awk '{print $2 " " $4}' || true)
  read -r cov ft <<<"${cov:-? ?}"
  units=$(find "$corpus" -type f | wc -l)
  artifacts=$(find "$findings" -type f | sort | paste -sd ' ' -)
  if [ "$rc" -ne 0 ] || [ -n "$artifacts" ]; then
    kind=$(grep -o -m1 -E "terminate called after throwing an instance of '[^']*'" "$log" ||
           grep -o -m1 -E 'ERROR: (AddressSanitizer|LeakSanitizer|libFuzzer): [a-z-]+( memory leaks)?|[^ ]+: runtime error|[^ ]+: invariant violated' "$log" ||
           true)
    if [ "$rc" -eq 124 ] || [ "$rc" -eq 137 ]; then kind="hang (killed after $((seconds + 120)) s)"; fi
    result="FOUND: ${kind:-exit $rc} -> ${artifacts:-no reproducer} (log: $log)"
  fi
  printf '%-16s %10s %6s %7s %7s  %s\n' "$t" "${execs:-?}" "$cov" "$ft" "$units" "$result" \
    >"$build/logs/$t.summary"
  [ "$result" = ok ]
}

for t in "${targets[@]}"; do
  [ -x "$build/fuzz/fuzz_$t" ] || { echo "fuzz: no target '$t' ($build/fuzz/fuzz_$t)" >&2; exit 2; }
done
parallel=${NERAF_FUZZ_PARALLEL:-1}
failed=0
running=0
for t in "${targets[@]}"; do
  if [ "$running" -ge "$parallel" ]; then
    wait -n || failed=1
    running=$((running - 1))
  fi
  run_target "$t" &
  running=$((running + 1))
done
while [ "$running" -gt 0 ]; do
  wait -n || failed=1
  running=$((running - 1))
done

echo
printf '%-16s %10s %6s %7s %7s  %s\n' target executions cov features corpus result
for t in "${targets[@]}"; do cat "$build/logs/$t.summary"; done
exit $failed
