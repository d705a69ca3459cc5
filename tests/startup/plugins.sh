#!/usr/bin/env bash
# Start-up: the program links none of the heavy optional libraries (pagmo, HDF5, assimp, Ceres,
# Open MPI, libsndfile, Highway: their loading costs every start, docs/PERFORMANCE.md "Start-up"); the
# commands that do not need them run without any plugin; each command that needs one, without
# it, fails with exit 1, naming the plugin and where it looked, and leaves no output; with the
# plugins (found beside the program) the same commands run.
# Usage: plugins.sh TROCHOMILL SOURCE_DIR
set -uo pipefail
bin=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0
bad() { echo "FAIL: $*"; fail=1; }

libs=$(ldd "$bin")
for lib in libpagmo libhdf5 libassimp libceres libmpi libsndfile libglog libcholmod libhwy; do
  if grep -q "$lib" <<<"$libs"; then bad "$bin links $lib"; fi
done

job=$src/examples/pivkin2025/trochoidal.toml
prog=$work/small.ngc
printf 'G21 G90 G17\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X10 F600\nG2 X20 Y0 I5 J0\nG1 Y10\nG0 Z5\nM2\n' >"$prog"
mkdir "$work/empty"

# Without any plugin: what needs none runs.
export TROCHOMILL_PLUGIN_DIR=$work/empty
"$bin" --version >/dev/null || bad "--version without plugins"
"$bin" check-gcode "$prog" >/dev/null || bad "check-gcode without plugins"
"$bin" analyze "$job" --set slot.length=3 >/dev/null || bad "analyze without plugins"

# needs PLUGIN OUTPUT COMMAND...: exit 1, the plugin and the place named, no OUTPUT.
needs() {
  local plugin=$1 out=$2
  shift 2
  local err rc
  err=$("$@" 2>&1 >/dev/null)
  rc=$?
  [[ $rc == 1 ]] || bad "$plugin missing: exit $rc, expected 1 ($*)"
  grep -q "libtrochomill_$plugin.so could not be loaded: $work/empty/libtrochomill_$plugin.so (not there)" <<<"$err" ||
    bad "$plugin missing: the message does not name the plugin and the place: $err"
  [[ ! -e $out ]] || bad "$plugin missing: $out was left behind"
}
needs sndfile "$work/a.wav" "$bin" synth-signal "$job" -o "$work/a.wav" --cycles 2
needs assimp "$work/a.stl" "$bin" insert "$job" -o "$work/a.stl"
needs rows "$work/s.json" "$bin" simulate "$job" --set slot.length=2 --cycles 0:1 --json "$work/s.json"
needs hdf5 "$work/sim" "$bin" simulate "$job" --set slot.length=2 --cycles 0:1 --out "$work/sim"
# calibrate reads the record, then fits with Ceres: the record from the fast forces (no plugin).
bergmann=$src/examples/bergmann2021/trochoidal.toml
"$bin" forces "$bergmann" --fast --cycles 1:2 --csv "$work/f.csv" >/dev/null ||
  bad "forces --fast without plugins"
needs ceres "$work/m.toml" "$bin" calibrate "$bergmann" --measured "$work/f.csv" \
  --fast --fit k_c --write "$work/m.toml"
needs nsga2 "$work/p.csv" "$bin" optimize "$job" --set slot.length=3 --var path.step=0.1:0.2 \
  --maximize cycle_mrr_mm3_per_min --minimize h_max_mm --max-evals 16 --population 8 --pareto "$work/p.csv"

# With the plugins beside the program: the same commands run.
unset TROCHOMILL_PLUGIN_DIR
"$bin" synth-signal "$job" -o "$work/a.wav" --cycles 2 >/dev/null 2>&1 || bad "synth-signal with its plugin"
"$bin" insert "$job" -o "$work/a.stl" >/dev/null 2>&1 || bad "insert with its plugin"
[[ -s $work/a.wav && -s $work/a.stl ]] || bad "the plugins' outputs are missing"
exit $fail
