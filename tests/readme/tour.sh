#!/usr/bin/env bash
# The README's tour, run as written: every command of its "A short tour" block, in order, in
# a fresh folder beside copies of the repository's examples and test programs, each must
# exit 0 (the README is this test's input, so the two cannot drift apart).
# Usage: tour.sh TROCHOMILL SOURCE_DIR
set -uo pipefail
T=$1
SRC=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1
ln -s "$SRC/examples" examples
ln -s "$SRC/tests" tests
# The tour's block: from "## A short tour" to the end of its first ```sh block; commands
# joined across trailing backslashes, comments and blank lines dropped.
awk '/^## A short tour/ {tour = 1; next}
     tour && /^```sh/ {inblock = 1; next}
     inblock && /^```/ {exit}
     inblock {print}' "$SRC/README.md" |
  sed -e 's/[[:space:]]*$//' |
  awk '/^#/ || /^$/ {next}
       /\\$/ {sub(/\\$/, ""); line = line $0; next}
       {print line $0; line = ""}' > commands
n=$(wc -l < commands)
[[ $n -ge 20 ]] || { echo "only $n commands found in the README's tour"; exit 1; }
fails=0
i=0
while IFS= read -r cmd; do
  i=$((i + 1))
  run=${cmd//build\/bin\/trochomill/$T}
  start=$(date +%s%N)
  if bash -c "$run" > out.txt 2>&1 < /dev/null; then
    printf 'ok   %2d %6d ms  %s\n' "$i" "$((($(date +%s%N) - start) / 1000000))" "${cmd:0:100}"
  else
    code=$?
    printf 'FAIL %2d (exit %d)  %s\n' "$i" "$code" "$cmd"
    sed 's/^/    /' out.txt | tail -5
    fails=$((fails + 1))
  fi
  # A warning the tour's own commands raise is a defect of the tour.
  if grep -q "^warning:" out.txt; then
    printf 'FAIL %2d warns: %s\n' "$i" "$(grep -m1 '^warning:' out.txt)"
    fails=$((fails + 1))
  fi
done < commands
echo "$n commands, $fails failed"
[[ $fails == 0 ]]
