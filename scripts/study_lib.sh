# Shared by the one-off studies (scripts/audio_average.sh, scripts/grid_few_shot.sh); sourced once
# STUDY (their name, for messages), NERAF, D (data folder) and R (runs folder) are set.

# study_check_tools MODULES PACKAGE: stops with one line naming the fix when build/neraf or a
# Python module the summary needs is missing
study_check_tools() {
  [ -x "$NERAF" ] || { echo "$STUDY: $NERAF: no such program; build it with scripts/build.sh" >&2; exit 1; }
  /usr/bin/python3 -c "import $1" 2>/dev/null || {
    echo "$STUDY: /usr/bin/python3 cannot import $1; install it with: apt-get install $2" >&2
    exit 1
  }
}

# synth_once PRESET NAME ARGS...: neraf synth into $D/NAME unless it is there already
synth_once() {
  [ -f "$D/$2/synth_info.json" ] || "$NERAF" synth --preset "$1" --out "$D/$2" --force --quiet "${@:3}" >/dev/null
}

# train_once NAME ARGS...: neraf train into $R/NAME (log $R/NAME.log) unless its done marker says
# it finished
train_once() {
  local run=$R/$1
  [ -f "$run/done" ] && return
  "$NERAF" train --out "$run" --force --quiet "${@:2}" >"$run.log" 2>&1 ||
    { echo "$STUDY: training $run failed; see $run.log" >&2; exit 1; }
  touch "$run/done"
}
