# Sourced by judge_equal_answers.sh and refit_critics.sh: one `sim --judge` of the lunar-critic-judge
# readings (docs/results/lunar-critic-judge/README.md), as all of them were run: 50 episodes from
# seed 1000, 8 actions around each step's, one thread. The summary is written whole or not at all
# (a `.partial` beside it until it ends) and a summary already there is kept, so a stopped script
# run again goes on where it was. Needs `bin` set to the dualrep binary.
#
#   judge_into TARGET SIM-ARGUMENTS...    # e.g. --checkpoint A.run --critic-from B.run
judge_into() {
  local target=$1
  shift
  [ -s "$target" ] && return 0
  "$bin" --threads 1 sim --task lunar-lander --judge --judge-actions 8 --episodes 50 --seed 1000 \
    "$@" > "$target.partial"
  mv "$target.partial" "$target"
  echo "$(date -u +%FT%TZ) $target"
}
