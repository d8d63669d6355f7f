#!/usr/bin/env bash
# Every option a message or help text of neraf's sources names ("--cache-dir", "pass --images
# DIR") must be an option some neraf command really has: an error that recommends a flag that does
# not exist sends the user nowhere. The options are read from every command's --help; the names
# from the string literals under src/neraf/. Other programs' flags quoted in messages are listed
# below with the program they belong to.
# Usage: flag_names.sh <path to neraf> <source dir>
set -u
NERAF=$1
SRC=$2
source "$(dirname "$0")/lib.sh"

# Not neraf's: what other tools take, quoted in messages or comments inside strings.
others="--stdout"  # espeak-ng --stdout (a WAV written to a pipe, io/audio_file.cpp)

# The commands and their subcommands, from the help texts themselves.
commands=()
sub_of() { "$NERAF" "$@" --help 2>/dev/null | awk 'toupper($0) ~ /^SUBCOMMANDS:/ {s = 1; next} s && /^  [a-z]/ {print $1}'; }
for c in $(sub_of); do
  commands+=("$c")
  for s in $(sub_of "$c"); do commands+=("$c $s"); done
done
[ "${#commands[@]}" -ge 10 ] || fail "found only ${#commands[@]} commands in neraf --help"

# Options: the lines of each help's option list ("  -h,--help", "  --steps INT ...").
{
  "$NERAF" --help
  for c in "${commands[@]}"; do
    # shellcheck disable=SC2086
    "$NERAF" $c --help
  done
} 2>/dev/null | grep -oE '^ +(-[a-zA-Z],)?--[a-z0-9][a-z0-9-]*' | grep -oE -- '--[a-z0-9-]+' |
  sort -u >"$TMP/options"
[ "$(wc -l <"$TMP/options")" -ge 50 ] || fail "found only $(wc -l <"$TMP/options") options"

# Names in string literals (one literal per match, escaped quotes kept inside), comment lines left
# out.
find "$SRC/src/neraf" -name '*.cpp' -o -name '*.h' | xargs sed -E 's#^[[:space:]]*//.*$##' |
  grep -oE '"([^"\\]|\\.)*"' |
  grep -oE -- '(^|[^a-zA-Z0-9_-])--[a-z][a-z0-9-]*' | grep -oE -- '--[a-z][a-z0-9-]*' |
  sort -u >"$TMP/named"
[ "$(wc -l <"$TMP/named")" -ge 50 ] || fail "found only $(wc -l <"$TMP/named") named options"

unknown=0
while read -r flag; do
  grep -qxF -- "$flag" "$TMP/options" && continue
  case " $others " in *" $flag "*) continue ;; esac
  where=$(grep -rnE --include='*.cpp' --include='*.h' -- "$flag([^a-z0-9-]|$)" "$SRC/src/neraf" |
    head -n 2 | cut -c 1-160)
  fail "$flag is named in a message but no neraf command has it: $where"
  unknown=$((unknown + 1))
done <"$TMP/named"
echo "$(wc -l <"$TMP/named") option names in messages, $(wc -l <"$TMP/options") options in" \
  "${#commands[@]} commands, $unknown unknown"
finish flag_names
