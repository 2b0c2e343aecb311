#!/usr/bin/env bash
# Installs the build tree into a temporary prefix and builds two consumers against it:
#   consumer/  find_package(jpcr COMPONENTS quadric) with every other dependency made unfindable,
#              so the math alone needs only Eigen;
#   pipeline/  find_package(jpcr) with everything: the README's embedding example, run, and every
#              installed header compiled.
# Usage: run_downstream.sh BUILD_DIR DOWNSTREAM_DIR CMAKE
set -euo pipefail
build=$1 downstream=$2 cmake=$3
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
"$cmake" --install "$build" --prefix "$tmp/prefix" > "$tmp/install.log"
ls "$tmp"/prefix/lib*/cmake/jpcr/jpcrConfig.cmake > /dev/null || fail "no jpcrConfig.cmake installed"
test -f "$tmp/prefix/include/jpcr/quadric/se3.hpp" || fail "headers not installed"
test -x "$tmp/prefix/bin/jpcr_eval" || fail "tools not installed"
# Headers only jpcr's own sources include (they pull in CUDA, Ceres, MRPT, yaml-cpp).
for internal in cuda/stream_events.hpp cuda/device_memory.hpp backend/point_to_plane_cost.hpp \
                io/yaml_reader.hpp io/mrpt_pose.hpp; do
  test ! -e "$tmp/prefix/include/jpcr/$internal" || fail "internal header installed: $internal"
done

build_consumer() {  # name source-dir cmake-options...
  local name=$1 source=$2; shift 2
  "$cmake" -S "$source" -B "$tmp/$name" -DCMAKE_PREFIX_PATH="$tmp/prefix" \
    -DCMAKE_BUILD_TYPE=Release "$@" > "$tmp/$name.configure.log" 2>&1 ||
    { cat "$tmp/$name.configure.log"; fail "$name: configure"; }
  "$cmake" --build "$tmp/$name" > "$tmp/$name.build.log" 2>&1 ||
    { cat "$tmp/$name.build.log"; fail "$name: build"; }
}

unfindable=()
for package in Ceres OpenCV CycloneDDS CUDAToolkit yaml-cpp mrpt-poses mrpt-obs Threads; do
  unfindable+=("-DCMAKE_DISABLE_FIND_PACKAGE_$package=TRUE")
done
build_consumer quadric "$downstream/consumer" "${unfindable[@]}"
"$tmp/quadric/consumer"

build_consumer pipeline "$downstream/pipeline"
grep -h "installed headers" "$tmp/pipeline.configure.log"
# A keyframe every centimetre of the walk, so that the back end refines within a few frames.
printf 'frontend:\n  tracker:\n    keyframe_translation: 0.01\npipeline:\n  window: 3\n' \
  > "$tmp/params.yaml"
"$tmp/pipeline/embedded_pipeline" "$tmp/params.yaml"
