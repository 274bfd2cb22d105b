#!/usr/bin/env bash
# The in-process comparison of pfe-default with the cores of the two ROS peers on the same
# CARMEN scans (the first PER_LOG FLASER scans of every shared log), built from their public
# sources. Usage, from the workspace root:
#
#   host-tests/peers/bench.sh [PEERS_DIR] [CARMEN_DIR]
#
# PEERS_DIR (default $PFE_PEER_SOURCES, else ../shared/peers) holds the peers' source trees as
# published: laser_line_extraction/ (its src/ and include/) and obstacle_detector/. A peer
# whose sources, compiler or libraries are absent is SKIPPED with the reason on stdout; the
# script still exits 0 (host timings are reported, not asserted). Needs: g++, Eigen 3 (Debian
# libeigen3-dev); Boost's array header is replaced by shim/ when Boost is absent.
set -u
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
PEERS=${1:-${PFE_PEER_SOURCES:-$ROOT/../shared/peers}}
CARMEN=${2:-$ROOT/../shared/data/carmen}
PER_LOG=${PER_LOG:-200}
REPS=${REPS:-11}
OUT=${CARGO_TARGET_DIR:-$ROOT/target}/peers
mkdir -p "$OUT"
skip() { echo "SKIPPED $1: $2"; }

if ! ls "$CARMEN"/*.log* >/dev/null 2>&1; then
  skip "every peer" "no CARMEN log in $CARMEN"; exit 0
fi
# pfe-default's in-process time on the same scans, once, when a peer is timed.
pfe_ns=""
pfe_time() {
  [ -n "$pfe_ns" ] && return
  local PFE=$ROOT/target/release/pfe
  [ -x "$PFE" ] || (cd "$ROOT" && cargo build --release -p pfe-cli >&2) || { echo "cannot build pfe" >&2; exit 1; }
  read -r pfe_ns pfe_scans pfe_beams <<<"$("$PFE" bench --only pfe-default --dataset carmen \
    --carmen "$CARMEN" --per-log "$PER_LOG" --reps "$REPS" --json --report-only 2>/dev/null |
    python3 -c 'import json,sys; d=json.load(sys.stdin)["datasets"][0]; m=[m for m in d["methods"] if m["method"]=="pfe-default"][0]; print("%.1f %d %d" % (m["ns_per_point"], d["scans"], d["points"]))')"
  echo "pfe-default (in process): $pfe_ns ns/beam on $pfe_scans scans, $pfe_beams beams"
}

scans() { for f in "$CARMEN"/*.log*; do printf "\nLOG\n"; zcat -f "$f"; done; }

# laser_line_extraction: its core (LineExtraction, line.cpp) is free of ROS.
LLE=$PEERS/laser_line_extraction
if [ ! -f "$LLE/src/line_extraction.cpp" ] || [ ! -f "$LLE/src/line.cpp" ]; then
  skip laser_line_extraction "no sources in $LLE (src/line_extraction.cpp, src/line.cpp)"
elif ! command -v g++ >/dev/null; then
  skip laser_line_extraction "no g++"
elif [ ! -d /usr/include/eigen3 ]; then
  skip laser_line_extraction "no Eigen 3 headers (/usr/include/eigen3: apt-get install libeigen3-dev)"
else
  shim=()
  echo '#include <boost/array.hpp>' | g++ -x c++ -fsyntax-only - 2>/dev/null || shim=(-I "$ROOT/host-tests/peers/shim")
  if g++ -O3 -DNDEBUG -std=c++17 -I "$LLE/include" -I /usr/include/eigen3 "${shim[@]}" \
      "$ROOT/host-tests/peers/laser_line_extraction_driver.cpp" "$LLE/src/line_extraction.cpp" \
      "$LLE/src/line.cpp" -o "$OUT/lle" 2>"$OUT/lle.log"; then
    pfe_time
    read -r _ s _ b _ l _ ns <<<"$(scans | "$OUT/lle" "$REPS" "$PER_LOG")"
    echo "laser_line_extraction core: $ns ns/beam on $s scans, $b beams, $l lines a scan;" \
      "pfe-default $(python3 -c "print('%.2f' % ($ns / $pfe_ns))")× faster (issue 42: ≥ 7)"
  else
    skip laser_line_extraction "it did not compile (see $OUT/lle.log)"
  fi
fi

# obstacle_detector: its extraction (ObstacleExtractor) is a ROS nodelet class whose header
# and source need roscpp, sensor_msgs, tf and its generated messages; no registry reachable
# here publishes them, so only the ROS-free utilities could be built, which are not its core.
OD=$PEERS/obstacle_detector
if [ ! -f "$OD/src/obstacle_extractor.cpp" ]; then
  skip obstacle_detector "no sources in $OD (src/obstacle_extractor.cpp)"
elif [ ! -f /opt/ros/noetic/include/ros/ros.h ] && [ ! -f /opt/ros/melodic/include/ros/ros.h ]; then
  skip obstacle_detector "its core ObstacleExtractor needs ROS 1 headers (roscpp, sensor_msgs, tf; none under /opt/ros) and Armadillo"
else
  skip obstacle_detector "building it against ROS 1 is not scripted yet"
fi
