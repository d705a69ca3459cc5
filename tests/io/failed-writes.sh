#!/usr/bin/env bash
# A write that fails (here: past the file size limit, `ulimit -f`, as a full disk fails it) in
# every kind of output: exit 1, a message naming the file, no temporary file or partial folder
# left (beside the output nor in TMPDIR), and an output already there kept as it was.
# Usage: failed-writes.sh TROCHOMILL EXAMPLES_DIR
set -uo pipefail
T=$1
EX=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export TMPDIR=$work/tmp
mkdir -p "$TMPDIR" "$work/out"
job=$EX/wagih2023/trochoidal.toml
fails=0
# check NAME OUTPUT(file or folder, as the message names it) LIMIT_KB -- COMMAND...
check() {
  local name=$1 out=$2 limit=$3
  shift 4
  rm -rf "$work/out" && mkdir -p "$work/out"
  # An earlier output of the same name: kept as it was.
  if [[ $out != */ ]]; then echo "earlier $name" > "$work/out/$out"; fi
  # The limit on the command alone; its messages go through pipes, which the limit spares.
  (cd "$work/out" && bash -c 'ulimit -f "$1"; shift; exec "$@"' _ "$limit" "$@" \
    > >(cat > "$work/stdout") 2> >(cat > "$work/stderr"))
  local code=$?
  sleep 0.1  # the pipes' readers finish
  local problems=""
  [[ $code == 1 ]] || problems+=" exit $code (want 1);"
  grep -q "cannot write '[^']*${out%/}" "$work/stderr" || problems+=" message does not name ${out%/};"
  if [[ $out != */ ]]; then
    [[ "$(cat "$work/out/$out")" == "earlier $name" ]] || problems+=" the earlier $out changed;"
  fi
  local left
  left=$(cd "$work/out" && find . -mindepth 1 ! -name "${out%/}" | head -3)
  [[ -z $left ]] || problems+=" left in the folder: $left;"
  left=$(find "$TMPDIR" -mindepth 1 | head -3)
  [[ -z $left ]] || problems+=" left in TMPDIR: $left;"
  if [[ -n $problems ]]; then
    echo "FAIL $name:$problems"
    sed 's/^/    /' "$work/stderr" | head -5
    fails=$((fails + 1))
  else
    echo "ok   $name: $(head -1 "$work/stderr")"
  fi
  rm -rf "${TMPDIR:?}"/*
}
check "G-code (plan)" slot.ngc 4 -- "$T" plan "$job" -o slot.ngc
check "CSV (path)" path.csv 4 -- "$T" path "$job" --csv path.csv
check "JSON (analyze)" a.json 4 -- "$T" analyze "$job" --json a.json
check "CSV (analyze)" a.csv 1 -- "$T" analyze "$job" --csv a.csv
check "HTML (report)" r.html 64 -- "$T" report "$job" -o r.html
check "WAV (synth-signal)" s.wav 4 -- "$T" synth-signal "$job" -o s.wav --cycles 2
check "STL (insert)" i.stl 4 -- "$T" insert "$job" -o i.stl
check "CSV (mechanism)" m.csv 4 -- "$T" mechanism "$job" --csv m.csv
check "HDF5 (simulate --out)" sim/ 400 -- "$T" simulate "$job" --cycles 3:4 --out sim
# A job without a [material] and one round of scheduling: the write is what is tested (with
# Pivkin's job each run took 60 s under the sanitizers, most of it the force model's summary;
# this one 13 s).
opt_job=$EX/curves/bend.toml
"$T" plan "$opt_job" --set machine.dialect=linuxcnc -o "$work/p.ngc" 2> /dev/null
check "G-code (optimize-feed)" f.ngc 4 -- "$T" optimize-feed --job "$opt_job" "$work/p.ngc" --rounds 1 -o f.ngc
check "HTML (optimize-feed)" f.html 16 -- "$T" optimize-feed --job "$opt_job" "$work/p.ngc" --rounds 1 -o - --html f.html
check "TOML (optimize)" best.toml 0 -- "$T" optimize "$job" --var path.step=0.5:1 --maximize cycle_mrr_mm3_per_min --max-evals 10 -o best.toml
# A full disk itself, where a private mount may be made (root, `unshare -m`): a 300 kB tmpfs.
if unshare -m true 2> /dev/null; then
  mkdir -p "$work/small"
  for cmd in "simulate $job --cycles 3:4 --out sim" "plan $job --set path.step=0.01 -o s.ngc"; do
    # shellcheck disable=SC2086  # the command's words
    out=$(unshare -m bash -c 'mount -t tmpfs -o size=300k tmpfs "$1" && cd "$1" && shift &&
                              "$@"; code=$?; echo "exit $code"; ls -A' _ "$work/small" "$T" $cmd 2>&1)
    if grep -q "^exit 1$" <<< "$out" && grep -q "No space left on device" <<< "$out" &&
       [[ $(sed -n '/^exit 1$/,$p' <<< "$out" | wc -l) == 1 ]]; then
      echo "ok   full disk: $(head -1 <<< "$out")"
    else
      echo "FAIL full disk ($cmd):"; sed 's/^/    /' <<< "$out" | head -5
      fails=$((fails + 1))
    fi
  done
else
  echo "skip full disk: no private mount here (unshare -m)"
fi
[[ $fails == 0 ]] || { echo "$fails output(s) not handled"; exit 1; }
