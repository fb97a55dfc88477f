#!/usr/bin/env bash
# Installs every Debian package the project needs (Debian 12). Idempotent and non-interactive:
# packages already installed are skipped, so a second run does nothing and takes a second.
# The lists live in deploy/packages/*.txt (one package a line, '#' comments), one file per area.
# Then the npm packages of the project's Node.js steps (tools/ifc_import: the IFC engine web-ifc;
# tools/mcap_check: Foxglove's MCAP reader, run by the bag tests; services/gui/app: the operator GUI's
# three.js, urdf-loader, esbuild and playwright-core) are installed from their committed lockfiles with `npm ci`, when node_modules is missing or
# older than the lockfile; nothing is fetched at run time.
# Usage: deploy/install-deps.sh [--check | --runtime]
#   --check: only report what is missing; exit 1 if any
#   --runtime: only what the stack needs to run (packages/runtime.txt), no npm step and no
#              kernel settings: the runtime image (deploy/image/Containerfile, deploy/Dockerfile)
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
check_only=0
runtime_only=0
case "${1:-}" in
  --check) check_only=1 ;;
  --runtime) runtime_only=1 ;;
  "") ;;
  *) echo "install-deps.sh: unknown argument '$1' (expected --check, --runtime or nothing)" >&2; exit 2 ;;
esac

lists=("$here"/packages/*.txt)
[ "$runtime_only" -eq 1 ] && lists=("$here/packages/runtime.txt")
mapfile -t wanted < <(cat "${lists[@]}" | sed 's/#.*//' | tr -s ' \t' '\n' | sed '/^$/d' | sort -u)

missing=()
for pkg in "${wanted[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$pkg")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#wanted[@]} packages already installed"
else
  echo "install-deps: missing ${#missing[@]} of ${#wanted[@]} packages: ${missing[*]}"
  [ "$check_only" -eq 1 ] && exit 1

  sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "install-deps: not root and no sudo; install as root: ${missing[*]}" >&2; exit 1; }
    sudo="sudo"
  fi
  export DEBIAN_FRONTEND=noninteractive
  # A fresh machine has no package lists yet; refresh them once (cheap when already recent).
  $sudo apt-get update -q
  $sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
  echo "install-deps: done"
fi
# The runtime image gets its npm packages and kernel settings from elsewhere (the staged tree;
# the host's sysctl: a container shares its host's network namespace).
[ "$runtime_only" -eq 1 ] && exit 0

# npm packages, one folder per Node.js step, from its committed package-lock.json. Quiet when
# node_modules is already newer than the lockfile.
# (A folder that is not there, as in the Docker build's first layer, is skipped.)
for dir in "$here/../tools/ifc_import" "$here/../tools/mcap_check" "$here/../services/gui/app"; do
  [ -f "$dir/package-lock.json" ] || continue
  dir=$(cd "$dir" && pwd)
  lock="$dir/package-lock.json"
  stamp="$dir/node_modules/.package-lock.json"
  if [ -f "$stamp" ] && [ "$stamp" -nt "$lock" ]; then
    continue
  fi
  if [ "$check_only" -eq 1 ]; then
    echo "install-deps: npm packages of $dir are missing or older than its lockfile" >&2
    exit 1
  fi
  if ! command -v npm >/dev/null; then
    echo "install-deps: npm not found; installing Debian's npm package"
    sudo=""
    [ "$(id -u)" -ne 0 ] && sudo="sudo"
    $sudo apt-get update -q  # the lists may be gone (the Docker image removes them)
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q --no-install-recommends npm
  fi
  echo "install-deps: npm ci in $dir"
  (cd "$dir" && npm ci --no-audit --no-fund --loglevel=error)
done

# Socket buffers: DDS on one machine runs over loopback UDP (libs/dds participant.cpp, no shared
# memory) and asks for 4 MiB buffers, which the kernel caps at net.core.rmem_max / wmem_max
# (Debian's default: 208 KiB, where two camera frames in three were lost). Raised here and kept
# in /etc/sysctl.d; where the kernel's settings cannot be changed (a container without the
# right), only a warning: the services warn too, and run.
want_buf=4194304
for key in rmem_max wmem_max; do
  have=$(cat /proc/sys/net/core/$key 2>/dev/null || echo 0)
  [ "$have" -ge "$want_buf" ] && continue
  if [ "$check_only" -eq 1 ]; then
    echo "install-deps: net.core.$key is $have, below $want_buf (DDS camera frames may be lost)" >&2
    continue
  fi
  sudo=""
  [ "$(id -u)" -ne 0 ] && command -v sudo >/dev/null && sudo="sudo"
  if $sudo sysctl -q -w "net.core.$key=$want_buf" 2>/dev/null; then
    echo "net.core.$key = $want_buf" | $sudo tee -a /etc/sysctl.d/60-concert-dds.conf >/dev/null 2>&1 || true
    echo "install-deps: net.core.$key raised from $have to $want_buf (DDS socket buffers)"
  else
    echo "install-deps: warning: net.core.$key is $have and cannot be raised here to $want_buf; large DDS samples (camera images) may be lost" >&2
  fi
done
