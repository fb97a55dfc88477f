#!/bin/sh
# Builds the operator GUI app into OUT_DIR: `npm ci` against the committed lockfile when
# node_modules is missing or older than it, then esbuild (build.mjs). Run by the build
# (services/gui/CMakeLists.txt); nothing is fetched when node_modules is current.
# Usage: app/build.sh OUT_DIR
set -eu
here=$(cd "$(dirname "$0")" && pwd)
out=${1:?usage: build.sh OUT_DIR}
stamp="$here/node_modules/.package-lock.json"
if [ ! -f "$stamp" ] || [ "$here/package-lock.json" -nt "$stamp" ]; then
  command -v npm >/dev/null || { echo "build.sh: npm not found (deploy/install-deps.sh installs it)" >&2; exit 1; }
  (cd "$here" && npm ci --no-audit --no-fund --loglevel=error)
fi
node "$here/build.mjs" "$out"
