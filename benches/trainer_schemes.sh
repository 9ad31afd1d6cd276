#!/bin/sh
# Paired cost per step of trainer schemes (issue 19): runs the schemes one after another, ROUNDS
# times, on the same organ, and prints each run's median step time and, per round, its ratio to
# the legacy run of that round. Usage: benches/trainer_schemes.sh ROUNDS [trainer flags...]
# e.g. benches/trainer_schemes.sh 5 --surface ../shared/meshes/sofa_liver2.obj
set -eu
T=${TRAINER:-target/release/trainer}
ROUNDS=${1:-5}; shift || true
med() { "$T" "$@" | sed -n 's/.*step time *median \([0-9.]*\) ms.*/\1/p'; }
for r in $(seq "$ROUNDS"); do
  l=$(med --scheme legacy "$@"); d=$(med "$@")
  echo "round $r legacy $l ms realtime $d ms ratio $(echo "$d / $l" | bc -l | cut -c1-5)"
done
