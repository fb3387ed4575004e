#!/usr/bin/env bash
# Writes the seed inputs fuzz/corpus/<target>/seed-* (committed). Run it again only to change the seeds; it
# overwrites seed-* files and leaves the inputs that scripts/fuzz merged in alone.
#   fuzz/make_seed_corpus.sh [TOOL]   TOOL: the ccd_fuzz_input encoder (default build-fuzz/fuzz/ccd_fuzz_input,
#                                     built by scripts/fuzz or `cmake --build build-fuzz --target ccd_fuzz_input`)
# CCD seeds: queries of the shared ccd-vertex-face data (../shared beside the repo) and hand-made degenerate
# ones; scene seeds: the demo scenes, the docs' complete example and broken variants of them.
# shellcheck disable=SC2016  # the single-quoted $ are sed's (last line), not the shell's
set -euo pipefail
cd "$(dirname "$0")/.."

tool=${1:-build-fuzz/fuzz/ccd_fuzz_input}
data=../shared/data/ccd-vertex-face/handcrafted
ccd=fuzz/corpus/ccd
scene=fuzz/corpus/scene_loader
mkdir -p "$ccd" "$scene"

# --- CCD: queries from the data files, by line number among the query lines (comments skipped) ------------
# seed_from_file NAME FILE LINE: encode that query as fuzz/corpus/ccd/seed-NAME.
seed_from_file() {
  grep -v '^#' "$data/$2.vf.txt" | sed -n "$3p" | "$tool" encode >"$ccd/seed-$1"
}
# unit-tests: hits and misses, including near misses at 2^-23.
for line in 1 13 25 50 75 100 125 150 175 200 225 250; do
  seed_from_file "unit-tests-$line" unit-tests "$line"
done
# Erleben's degenerate scenes: the first hit of each (vertex on edge, sliding contact), and two misses.
seed_from_file erleben-cube-cliff-edges-33 erleben-cube-cliff-edges 33
seed_from_file erleben-cube-internal-edges-25 erleben-cube-internal-edges 25
seed_from_file erleben-sliding-spike-8 erleben-sliding-spike 8
seed_from_file erleben-sliding-wedge-115 erleben-sliding-wedge 115
seed_from_file erleben-spike-crack-7 erleben-spike-crack 7
seed_from_file erleben-spike-hole-2 erleben-spike-hole 2
seed_from_file erleben-spike-wedge-10 erleben-spike-wedge 10
seed_from_file erleben-spikes-4 erleben-spikes 4
seed_from_file erleben-wedge-crack-13 erleben-wedge-crack 13
seed_from_file erleben-wedges-19 erleben-wedges 19
seed_from_file erleben-spikes-1-miss erleben-spikes 1
seed_from_file erleben-wedges-1-miss erleben-wedges 1

# --- CCD: hand-made degenerate queries ---------------------------------------------------------------------
# seed NAME "24 numbers" [FLAGS ARGUMENTS...]: order p_t0 a_t0 b_t0 c_t0 p_t1 a_t1 b_t1 c_t1 (x y z each).
seed() {
  local name=$1 query=$2
  shift 2
  echo "$query" | "$tool" encode "$@" >"$ccd/seed-$name"
}
tri0="0 0 0  4 0 0  0 4 0"  # static triangle in z = 0
seed head-on-through-face "1 1 2  $tri0  1 1 -2  $tri0"
seed touches-at-t1 "1 1 2  $tri0  1 1 0  $tri0"
seed starts-on-vertex "0 0 0  $tri0  0 0 3  $tri0"
seed through-edge-midpoint "2 0 1  $tri0  2 0 -1  $tri0"
seed coplanar-slides-into-face "-2 1 0  $tri0  1 1 0  $tri0"
seed coplanar-slides-along-edge-line "-2 0 0  $tri0  -1 0 0  $tri0"
seed coplanar-misses "-2 -1 0  $tri0  5 -1 0  $tri0"
seed static-inside "1 1 0  $tri0  1 1 0  $tri0"
seed zero-area-segment-crossed "2 1 1  0 0 0  4 0 0  2 0 0  2 -1 -1  0 0 0  4 0 0  2 0 0"
seed point-triangle-crossed "1 1 1  1 1 0  1 1 0  1 1 0  1 1 -1  1 1 0  1 1 0  1 1 0"
seed near-miss-2p-30 "4.0000000009313226 0 1  $tri0  4.0000000009313226 0 -1  $tri0"
seed plane-flips-through-point "1 1 0  0 0 -1  4 0 -1  0 4 -1  1 1 0  0 0 1  4 0 1  0 4 1"
seed rotating-triangle-grazes "0 0 1  -4 -4 0  4 -4 0  0 4 0  0 0 1  -4 -4 0  4 -4 2  0 4 2"
# The ends of the raw range of ccd_fuzz_input.hpp (2^64 - 2^11 and 2^-65).
seed huge "18446744073709549568 0 0  0 0 0  1 0 0  0 1 0  -18446744073709549568 0 0  0 0 0  1 0 0  0 1 0"
seed tiny "2.710505431213761e-20 0 1  0 0 0  1 0 0  0 1 0  0 0 -1  0 0 0  1 0 0  0 1 0"
seed nan "nan 0 0  $tri0  0 0 0  $tri0"
seed infinity "0 0 1  $tri0  0 0 -inf  $tri0"
# Structure flags (see ccd_fuzz_input.hpp): point on an edge at t0 and on a vertex at t1, coplanar; a
# zero-area triangle at t1 with a rigidly moving triangle; everything at once.
seed flags-edge-then-vertex-coplanar "3 3 3  1 0 0  0 5 0  -3 -2 0  7 7 7  2 1 0  1 6 0  -2 -1 0" 224 3 1
seed flags-rigid-degenerate-t1 "1 1 2  0 0 0  4 0 0  0 4 0  1 1 -2  0 1 1  4 0 0  0 4 0" 18 3
seed flags-all "1 2 3  4 5 6  7 8 9  1 1 1  -1 -2 -3  -4 -5 -6  -7 -8 -9  0 0 0" 255 0 3 13 14

# --- Scene loader: valid scenes and broken variants -----------------------------------------------------
cp demos/scenes/dam_break.json "$scene/seed-dam_break.json"
cp demos/scenes/hydrostatic_tank.json "$scene/seed-hydrostatic_tank.json"
# The complete example of docs/scenes.md (nozzle emitter, kill region, every fluid key).
sed -n '/^## A complete example/,/^```$/p' docs/scenes.md | sed '1,/^```json$/d;/^```$/d' \
  >"$scene/seed-docs_complete_example.json"
# variant NAME SED_EXPRESSION: dam_break.json edited by sed.
variant() {
  sed "$2" demos/scenes/dam_break.json >"$scene/seed-broken-$1.json"
}
variant truncated '12,$d'
variant negative_spacing 's/"particle_spacing": 0.05/"particle_spacing": -0.05/'
variant unknown_key 's/"rest_density"/"rest_densty"/'
variant wrong_type 's/"duration": 3.0/"duration": "3"/'
variant unknown_solver 's/"pcisph",/"sph",/'
variant min_above_max 's/"max": \[1.0, 1.0, 1.0\]/"max": [-1.0, 1.0, 1.0]/'
variant huge_number 's/"dt": 0.005/"dt": 1e308/'
variant iterations_float 's/"max_iterations": 100/"max_iterations": 100.5/'
variant gravity_short 's/\[0.0, -9.81, 0.0\]/[0.0, -9.81]/'
variant unknown_effect 's/\["viscosity"\]/["viscosity", "surface_tension"]/'
variant null_emitters 's/"emitters": \[/"emitters": null, "x": [/'
printf '{}' >"$scene/seed-empty_object.json"
printf '[1, 2, 3]' >"$scene/seed-top_level_array.json"
printf '{"fluid": {"particle_spacing": 0.02}, "emitters": [{"type": "nozzle", "direction": [0, 0, 0]}]}' \
  >"$scene/seed-zero_direction.json"
printf '{"boundaries": [{"type": "plane", "size": [1], "normal": [0, 1e-320, 0]}]}' >"$scene/seed-plane.json"
printf '{"kill_regions": [{"type": "box", "min": [0, 0, 0], "max": [0, 1, 1]}], "time": {"dt": 2}}' \
  >"$scene/seed-kill_box_time.json"
printf '{"fluid": {"wcsph": {"speed_of_sound": null, "exponent": 0.5}, "pressure_solver": "wcsph"}}' \
  >"$scene/seed-wcsph.json"
printf '{"emitters": [{"type": "nozzle", "max_particles": 18446744073709551616}]}' \
  >"$scene/seed-max_particles_overflow.json"

ccd_seeds=("$ccd"/seed-*)
scene_seeds=("$scene"/seed-*)
echo "seeds: ${#ccd_seeds[@]} in $ccd, ${#scene_seeds[@]} in $scene"
