#!/usr/bin/env bash
# The checksums of what the runtime image is made of, one "sha256  path" line each: the build
# tree's executables and GUI app (build/...), the module database, configuration and entry
# point from the source tree (src/...). The image keeps them in /opt/concert/manifest.sha256;
# the compose test compares them with the trees it tests, so an image older than either fails.
# Usage: deploy/image/manifest.sh BUILD_DIR
set -euo pipefail
src=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
build=$(cd "$1" && pwd)
{
  (cd "$build"
   files=(tools/concert/concert services/gui/app/*)
   for s in robot safety discovery modelgen nav planner drill collab surface_finish gui; do
     files+=("services/$s/concert_$s")
   done
   sha256sum "${files[@]}" | sed 's|  |  build/|')
  (cd "$src" && find data/module_db services/*/config deploy/dds deploy/demo deploy/image deploy/install-deps.sh \
     deploy/packages/runtime.txt tools/ifc_import/ifc_import.mjs tools/ifc_import/package-lock.json -type f -print0 \
     | xargs -0 sha256sum | sed 's|  |  src/|')
} | sort -k2
