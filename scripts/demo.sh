#!/usr/bin/env bash
# Builds the library (cargo, through CMake) and runs the C demo. Usage: scripts/demo.sh
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
. "$root/scripts/deps.sh"
need_build_tools
build="$root/build/demo"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" --target opccomn_demo -j2
"$build/bin/opccomn_demo"
