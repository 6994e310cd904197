#!/usr/bin/env bash
# Sets up (packages + build) and runs every test. Exit status is non-zero if any test fails.
set -euo pipefail
cd "$(dirname "$0")/.."
deploy/setup.sh
BUILD_DIR=${BUILD_DIR:-build}
ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$(nproc)" "$@"
