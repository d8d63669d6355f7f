# Shared by the CLI test scripts: `source` it after setting NERAF and ASSETS.
# Provides $TMP (removed on exit), fail, expect_exit, expect_in, expect_file and finish.
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
failures=0

fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
# expect_exit CODE CMD...: runs CMD, captures stdout/stderr in $TMP/out, $TMP/err
expect_exit() {
  local want=$1; shift
  "$@" >"$TMP/out" 2>"$TMP/err"
  local got=$?
  [ "$got" -eq "$want" ] || fail "'$*' exited $got, expected $want; stderr: $(tail -c 400 "$TMP/err")"
}
expect_in() {  # expect_in FILE PATTERN
  grep -q -- "$2" "$1" || fail "expected '$2' in $(basename "$1"): $(tail -c 300 "$1")"
}
expect_file() { [ -s "$1" ] || fail "expected a non-empty $1"; }
finish() {  # finish NAME: the summary line and the exit status
  if [ "$failures" -gt 0 ]; then
    echo "$failures $1 check(s) failed"
    exit 1
  fi
  echo "all $1 checks passed"
}
