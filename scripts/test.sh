#!/usr/bin/env bash
# Sets up and builds softbake if needed, then runs the whole test suite with ctest.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/setup.sh
ctest --test-dir "${SOFTBAKE_BUILD_DIR:-build}" --output-on-failure -j"$(nproc)"
