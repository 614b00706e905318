#!/bin/sh
# The page's one number-formatting function (web/src/format.js, fmt) under node: fixed cases
# (tiny, huge, negative, integers, exponents) and a sweep read back by Number()
# (tests/webfmt.mjs).  Needs node (make deps); a missing node is a failure.
set -u
cd "$(dirname "$0")/.."
if ! command -v node >/dev/null 2>&1; then
    echo "FAIL webfmt: node is missing (make deps installs it)"
    echo "0 passed, 1 failed"
    exit 1
fi
exec node tests/webfmt.mjs
