#!/usr/bin/env bash
# Lays out what the runtime image holds, from a build tree, in OUT/root (the image's /), with
# the two files its package step needs in OUT/deploy. Used by `make image` (deploy/image/build.sh,
# on the machine's build tree) and by deploy/Dockerfile (inside its build stage), so both
# images are the same.
#   /usr/local/bin      concert, concert_<service> for every service of `concert up` (stripped),
#                       concert-entrypoint
#   /opt/concert/       module_db, gui/app (the built web app), ifc_import (script + node_modules)
#   /etc/concert/       <service>/ the services' parameter files, drill/ its patterns,
#                       dds/ the Fast DDS profile, demo/ the demo assemblies
# Usage: deploy/image/stage.sh BUILD_DIR OUT_DIR
set -euo pipefail

[ $# -eq 2 ] || { echo "usage: $0 BUILD_DIR OUT_DIR" >&2; exit 2; }
src=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
build=$(cd "$1" && pwd) || { echo "stage: build folder '$1' not found (run make build)" >&2; exit 1; }
out=$2

services=(robot safety discovery modelgen nav planner drill collab surface_finish gui)
missing=()
for s in "${services[@]}"; do
  [ -x "$build/services/$s/concert_$s" ] || missing+=("services/$s/concert_$s")
done
[ -x "$build/tools/concert/concert" ] || missing+=("tools/concert/concert")
[ -f "$build/services/gui/app/index.html" ] || missing+=("services/gui/app/index.html")
[ -d "$src/tools/ifc_import/node_modules" ] || missing+=("$src/tools/ifc_import/node_modules (deploy/install-deps.sh)")
if [ ${#missing[@]} -gt 0 ]; then
  echo "stage: not built in $build: ${missing[*]} (run make build)" >&2
  exit 1
fi

rm -rf "$out"
root="$out/root"
mkdir -p "$root/usr/local/bin" "$root/opt/concert" "$root/etc/concert" "$out/deploy/packages"

# Executables without their debug sections: the build tree's are RelWithDebInfo (about 1 GB
# together); the image needs what runs.
for s in "${services[@]}"; do
  strip --strip-debug -o "$root/usr/local/bin/concert_$s" "$build/services/$s/concert_$s"
done
strip --strip-debug -o "$root/usr/local/bin/concert" "$build/tools/concert/concert"
install -m 0755 "$src/deploy/image/concert-entrypoint" "$root/usr/local/bin/concert-entrypoint"

cp -r "$src/data/module_db" "$root/opt/concert/module_db"
mkdir -p "$root/opt/concert/gui"
cp -r "$build/services/gui/app" "$root/opt/concert/gui/app"
mkdir -p "$root/opt/concert/ifc_import"
cp -r "$src/tools/ifc_import/ifc_import.mjs" "$src/tools/ifc_import/package.json" \
      "$src/tools/ifc_import/package-lock.json" "$src/tools/ifc_import/node_modules" \
      "$root/opt/concert/ifc_import/"

for s in robot safety discovery nav planner drill; do
  mkdir -p "$root/etc/concert/$s"
  cp "$src/services/$s/config/"*.yaml "$root/etc/concert/$s/"
done
cp -r "$src/deploy/dds" "$root/etc/concert/dds"
cp -r "$src/deploy/demo" "$root/etc/concert/demo"
mkdir -p "$root/var/lib/concert/model" "$root/var/lib/concert/safety"

# Which build the image holds: the checksums of the build tree's executables, so a test can
# tell an image older than the tree (deploy/image/manifest.sh).
"$src/deploy/image/manifest.sh" "$build" > "$root/opt/concert/manifest.sha256"

cp "$src/deploy/install-deps.sh" "$out/deploy/install-deps.sh"
cp "$src/deploy/packages/runtime.txt" "$out/deploy/packages/runtime.txt"
cp "$src/deploy/image/Containerfile" "$out/Containerfile"
echo "stage: $(du -sh "$root" | cut -f1) in $out/root"
