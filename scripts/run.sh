#!/bin/sh
# `make run`: starts the daemon in the foreground with the embedded SQLite default
# (./cellar.db) on 127.0.0.1:8080; CELLAR_* variables and extra arguments (make run
# ARGS="--listen 0.0.0.0:8080") override.  Ctrl-C (SIGINT) or SIGTERM drains and stops it.
set -eu
B=${1:-build}
shift || true
exec "$B/cellard" "$@"
