#!/usr/bin/env bash
# Installs the build tree into a temporary prefix and builds a consumer against it.
set -euo pipefail
build=$1 consumer=$2 cmake=$3
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
"$cmake" --install "$build" --prefix "$tmp/prefix" > "$tmp/install.log"
ls "$tmp"/prefix/lib*/cmake/jpcr/jpcrConfig.cmake > /dev/null || { echo "no jpcrConfig.cmake installed"; exit 1; }
test -f "$tmp/prefix/include/jpcr/quadric/se3.hpp" || { echo "headers not installed"; exit 1; }
test -x "$tmp/prefix/bin/jpcr_eval" || { echo "tools not installed"; exit 1; }
"$cmake" -S "$consumer" -B "$tmp/build" -DCMAKE_PREFIX_PATH="$tmp/prefix" -DCMAKE_BUILD_TYPE=Release > "$tmp/configure.log" || { cat "$tmp/configure.log"; exit 1; }
"$cmake" --build "$tmp/build" > "$tmp/build.log" 2>&1 || { cat "$tmp/build.log"; exit 1; }
"$tmp/build/consumer"
