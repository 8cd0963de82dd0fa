# Shared by scripts/fuzz-smoke and scripts/fuzz-campaign (sourced, not run).
# Builds the fuzz preset, makes the seed corpora from the shared data excerpts and runs targets.
#
# Layout (all under build/fuzz, never committed):
#   corpus/<target>/    seeds (seed_*) generated here from ../shared/data and tests/fuzz/seeds,
#                       plus what libFuzzer adds while fuzzing
#   findings/<target>/  crash-*, leak-*, timeout-*, oom-* inputs written by libFuzzer
#   logs/<target>.log   the last run's output
# Environment: IMUMATCH_DATA_DIR (default ../shared/data beside the checkout).

FUZZ_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
FUZZ_BUILD=$FUZZ_ROOT/build/fuzz
FUZZ_DATA=${IMUMATCH_DATA_DIR:-$FUZZ_ROOT/../shared/data}
FUZZ_TEXT_MAX_LEN=4096
FUZZ_IMAGE_MAX_LEN=16384

fuzz_build() {
  (cd "$FUZZ_ROOT" && cmake --preset fuzz >/dev/null && cmake --build --preset fuzz) >&2
}

# "name path" lines of the built targets.
fuzz_targets() { cat "$FUZZ_BUILD/tests/fuzz/targets.txt"; }

fuzz_max_len() {
  case $1 in
    load_image | load_depth | png_decoder) echo "$FUZZ_IMAGE_MAX_LEN" ;;
    *) echo "$FUZZ_TEXT_MAX_LEN" ;;
  esac
}

# ----- seed corpora ---------------------------------------------------------------------------

# seed <target> <name>: stdin -> corpus/<target>/seed_<name>
seed() {
  mkdir -p "$FUZZ_BUILD/corpus/$1"
  cat >"$FUZZ_BUILD/corpus/$1/seed_$2"
}

# Named seed of a multi-file target: "<file name>\n<content from stdin>".
named_seed() {
  { printf '%s\n' "$3"; cat; } | seed "$1" "$2"
}

# EuRoC "ns,..." rows -> "seconds ..." (TUM style), keeping the given 1-based columns.
ns_to_seconds() {
  awk -F, -v cols="$1" 'BEGIN { n = split(cols, c, " ") }
    /^#/ || NF < 2 { next }
    { t = $1; s = substr(t, 1, length(t) - 9) "." substr(t, length(t) - 8); line = s
      for (i = 1; i <= n; i++) line = line " " $(c[i]); print line }'
}

# EuRoC ground truth (ts, p xyz, q wxyz, ...) -> TUM trajectory "t tx ty tz qx qy qz qw".
euroc_gt_to_tum() {
  ns_to_seconds "2 3 4 6 7 8 5"
}

fuzz_make_seeds() {
  local d=$FUZZ_DATA mh=$FUZZ_DATA/euroc_mh05_flight/mav0 v1=$FUZZ_DATA/euroc_v101_excerpt/mav0
  local tum=$FUZZ_DATA/tum_fr1_xyz_pair
  # Committed hand-written seeds.
  local dir
  for dir in "$FUZZ_ROOT"/tests/fuzz/seeds/*/; do
    [ -d "$dir" ] || continue
    local t
    t=$(basename "$dir")
    mkdir -p "$FUZZ_BUILD/corpus/$t"
    local f
    for f in "$dir"*; do cp "$f" "$FUZZ_BUILD/corpus/$t/seed_$(basename "$f")"; done
  done
  if [ ! -d "$mh" ] || [ ! -d "$v1" ] || [ ! -d "$tum" ]; then
    echo "fuzz: shared data not found in $d (set IMUMATCH_DATA_DIR); committed seeds only" >&2
    return 0
  fi
  local seq m
  for seq in mh05 v101; do
    if [ $seq = mh05 ]; then m=$mh; else m=$v1; fi
    # TUM style text built from the EuRoC rows (the TUM excerpt has no lists).
    head -n 25 "$m/cam0/data.csv" | ns_to_seconds "2" | sed 's| | rgb/|' | seed tum_file_list $seq
    head -n 40 "$m/imu0/data.csv" | ns_to_seconds "5 6 7" | seed tum_accelerometer $seq
    head -n 30 "$m/imu0/data.csv" | ns_to_seconds "2 3 4 5 6 7" | seed imu_text $seq
    head -n 40 "$m/imu0/data.csv" | seed euroc_imu $seq
    head -n 40 "$m/cam0/data.csv" | seed euroc_image_list $seq
    seed euroc_camera_yaml $seq <"$m/cam0/sensor.yaml"
    seed euroc_imu_yaml $seq <"$m/imu0/sensor.yaml"
    head -n 30 "$m/imu0/data.csv" | named_seed euroc_dataset imu_$seq imu0/data.csv
    named_seed euroc_dataset cam_$seq cam0/sensor.yaml <"$m/cam0/sensor.yaml"
    named_seed euroc_dataset imuyaml_$seq imu0/sensor.yaml <"$m/imu0/sensor.yaml"
    head -n 8 "$m/cam0/data.csv" | named_seed euroc_dataset list_$seq cam0/data.csv
  done
  local gt=$mh/state_groundtruth_estimate0/data.csv
  head -n 40 "$mh/depth0/data.csv" | seed euroc_depth_list mh05
  seed euroc_depth_yaml mh05 <"$mh/depth0/sensor.yaml"
  head -n 15 "$gt" | seed euroc_groundtruth mh05
  head -n 15 "$gt" | cut -d, -f1-8 | seed euroc_poses mh05
  head -n 15 "$gt" | named_seed euroc_dataset gt_mh05 state_groundtruth_estimate0/data.csv
  head -n 4 "$mh/depth0/data.csv" | named_seed euroc_dataset depth_mh05 depth0/data.csv
  named_seed euroc_dataset depthyaml_mh05 depth0/sensor.yaml <"$mh/depth0/sensor.yaml"
  # Every 20th ground-truth row (10 Hz, like TUM's mocap) as a TUM trajectory.
  # (awk stops by itself: with pipefail, a writer cut off by head would fail the script.)
  awk 'NR % 20 == 2 && ++n <= 40' "$gt" | euroc_gt_to_tum | seed tum_trajectory mh05
  awk 'NR % 4 == 2 && ++n <= 30' "$gt" | euroc_gt_to_tum | seed tum_dataset raw_gt_mh05
  named_seed tum_dataset gt_mh05 groundtruth.txt <"$FUZZ_BUILD/corpus/tum_dataset/seed_raw_gt_mh05"
  named_seed synthetic_sequence gt_mh05 groundtruth.txt \
    <"$FUZZ_BUILD/corpus/tum_dataset/seed_raw_gt_mh05"
  head -n 30 "$mh/imu0/data.csv" | ns_to_seconds "2 3 4 5 6 7" |
    named_seed synthetic_sequence imu_mh05 imu.txt
  head -n 8 "$mh/cam0/data.csv" | ns_to_seconds "2" | sed 's| | rgb/|' |
    named_seed tum_dataset rgb_mh05 rgb.txt
  head -n 8 "$mh/depth0/data.csv" | ns_to_seconds "2" | sed 's| | depth/|' |
    named_seed tum_dataset depth_mh05 depth.txt
  head -n 12 "$mh/imu0/data.csv" | ns_to_seconds "5 6 7" |
    named_seed tum_dataset accel_mh05 accelerometer.txt
  {
    head -n 20 "$mh/cam0/data.csv" | ns_to_seconds "2" | sed 's| | rgb/|'
    printf '%%%%\n'
    head -n 20 "$mh/depth0/data.csv" | ns_to_seconds "2" | sed 's| | depth/|'
  } | seed tum_association mh05
  # The TUM pair's pose files, and the same poses as a two-line trajectory.
  seed tum_pose prev <"$tum/pose_prev.txt"
  seed tum_pose curr <"$tum/pose_curr.txt"
  { printf '1305031102.175304 '; cat "$tum/pose_prev.txt"; printf '\n1305031102.211214 ';
    cat "$tum/pose_curr.txt"; echo; } | seed tum_trajectory pair
  # Small crops of the real images in every format OpenCV writes here.
  local cam_images=("$mh"/cam0/data/*.png) depth_images=("$mh"/depth0/data/*.png)
  "$FUZZ_BUILD/tests/fuzz/imumatch_fuzz_image_seeds" "$FUZZ_BUILD/corpus/load_image" \
    "$FUZZ_BUILD/corpus/load_depth" "$tum/img_prev.png" "$tum/dep_prev.png" \
    "${cam_images[0]}" "${depth_images[0]}" >/dev/null
  # Renamed to seed_* so that libFuzzer's own files are told apart.
  local f
  for dir in "$FUZZ_BUILD/corpus/load_image" "$FUZZ_BUILD/corpus/load_depth"; do
    for f in "$dir"/*.*; do
      [ -e "$f" ] && mv "$f" "$dir/seed_$(basename "$f")"
    done
  done
  # The PNG decoder's corpus: the PNG seeds of both.
  mkdir -p "$FUZZ_BUILD/corpus/png_decoder"
  for f in "$FUZZ_BUILD"/corpus/load_image/seed_*.png "$FUZZ_BUILD"/corpus/load_depth/seed_*.png; do
    [ -e "$f" ] && cp "$f" "$FUZZ_BUILD/corpus/png_decoder/$(basename "$(dirname "$f")")_$(basename "$f")"
  done
  return 0
}

# ----- running --------------------------------------------------------------------------------

# A target killed by a crash leaves its scratch folder (fuzz_util.h) behind: remove those whose
# process is gone.
fuzz_clean_scratch() {
  local d
  for d in /dev/shm/imumatch_fuzz_* "${TMPDIR:-/tmp}"/imumatch_fuzz_*; do
    [ -d "$d" ] || continue
    kill -0 "${d##*_}" 2>/dev/null || rm -rf "$d"
  done
}

# fuzz_run <name> <binary> <libFuzzer options...>: runs one target on its corpus, crash inputs to
# findings/<name>/, output to logs/<name>.log. Sets FUZZ_EXECS, FUZZ_SECONDS, FUZZ_RESULT (ok,
# crash, uncaught-exception, asan, ubsan, leak, timeout, oom) and FUZZ_ARTIFACT.
fuzz_run() {
  local name=$1 bin=$2
  shift 2
  local corpus=$FUZZ_BUILD/corpus/$name findings=$FUZZ_BUILD/findings/$name
  local log=$FUZZ_BUILD/logs/$name.log
  mkdir -p "$corpus" "$findings" "$(dirname "$log")"
  local start end rc
  start=$(date +%s.%N)
  # libjpeg's warnings about corrupt input (one line per input) are dropped from the log.
  "$bin" -timeout=10 -rss_limit_mb=2048 -max_len="$(fuzz_max_len "$name")" -print_final_stats=1 \
    -artifact_prefix="$findings/" "$@" "$corpus" 2>&1 |
    sed -e '/^Corrupt JPEG data: /d' -e '/^Premature end of JPEG file$/d' >"$log" &&
    rc=0 || rc=${PIPESTATUS[0]}
  end=$(date +%s.%N)
  fuzz_clean_scratch
  FUZZ_SECONDS=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.0f", b - a }')
  FUZZ_EXECS=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  if [ -z "$FUZZ_EXECS" ]; then  # no final stats after a crash: the last "#N" status line
    FUZZ_EXECS=$(sed -n 's/^#\([0-9][0-9]*\).*/\1/p' "$log" | tail -n 1)
  fi
  FUZZ_EXECS=${FUZZ_EXECS:-0}
  FUZZ_ARTIFACT=$(sed -n 's/.*Test unit written to \(.*\)$/\1/p' "$log" | tail -n 1)
  if [ $rc -eq 0 ]; then
    FUZZ_RESULT=ok
  elif grep -q 'ERROR: libFuzzer: timeout' "$log"; then
    FUZZ_RESULT=timeout
  elif grep -q 'ERROR: libFuzzer: out-of-memory' "$log"; then
    FUZZ_RESULT=oom
  elif grep -q 'ERROR: LeakSanitizer' "$log"; then
    FUZZ_RESULT=leak
  elif grep -q 'runtime error:' "$log"; then
    FUZZ_RESULT=ubsan
  elif grep -q 'ERROR: AddressSanitizer' "$log"; then
    FUZZ_RESULT=asan
  elif grep -qE "terminate called after throwing|terminating due to uncaught exception" "$log"; then
    FUZZ_RESULT=uncaught-exception
  else
    FUZZ_RESULT="crash(rc=$rc)"
  fi
}
