#!/usr/bin/env bash
# `make image`: the CONCERT runtime image from what `make build` built, without compiling
# again. Steps, each printed with its time:
#   1. stage the build tree's executables, the module database, configuration, the GUI app
#      and the IFC step's node modules (deploy/image/stage.sh) into BUILD_DIR/image;
#   2. the Debian 12 base image, made once offline from Debian's packages with mmdebstrap
#      (from this machine's apt sources) and imported as localhost/concert/debian:12;
#   3. the image (deploy/image/Containerfile): the runtime packages (packages/runtime.txt),
#      then the staged tree;
#   4. a check inside it: every executable finds its libraries and answers --help.
# Usage: deploy/image/build.sh [BUILD_DIR]
# Environment: CONCERT_IMAGE (default concert/stack:latest), CONCERT_ENGINE (podman or docker;
# default podman when installed), CONCERT_BASE_IMAGE (default localhost/concert/debian:12).
set -euo pipefail

src=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
build=${1:-$src/build}
image=${CONCERT_IMAGE:-concert/stack:latest}
base=${CONCERT_BASE_IMAGE:-localhost/concert/debian:12}
engine=${CONCERT_ENGINE:-}
if [ -z "$engine" ]; then
  if command -v podman >/dev/null; then engine=podman
  elif command -v docker >/dev/null; then engine=docker
  else
    echo "image: neither podman nor docker is installed (deploy/install-deps.sh installs podman)" >&2
    exit 1
  fi
fi
if [ "$engine" = podman ] && [ -z "${CONTAINERS_CONF:-}" ]; then
  export CONTAINERS_CONF="$src/deploy/podman/containers.conf"
fi

t0=$(date +%s)
step() { echo "image: [$(( $(date +%s) - t0 )) s] $*"; }

step "1/4 staging $build into $build/image"
"$src/deploy/image/stage.sh" "$build" "$build/image"

if "$engine" image inspect "$base" >/dev/null 2>&1; then
  step "2/4 base image $base is there"
else
  command -v mmdebstrap >/dev/null || { echo "image: mmdebstrap is not installed (deploy/install-deps.sh)" >&2; exit 1; }
  sources=/etc/apt/sources.list.d/debian.sources
  [ -f "$sources" ] || sources=/etc/apt/sources.list
  [ -f "$sources" ] || { echo "image: no apt sources on this machine (/etc/apt/sources.list.d/debian.sources or /etc/apt/sources.list)" >&2; exit 1; }
  step "2/4 base image $base: mmdebstrap bookworm from $sources"
  tar=$(mktemp --tmpdir concert-debian-XXXXXX.tar)
  trap 'rm -f "$tar"' EXIT
  mmdebstrap --variant=minbase --quiet bookworm "$tar" "$sources"
  quiet=(); [ "$engine" = podman ] && quiet=(--quiet)  # docker import has no such option
  "$engine" import "${quiet[@]}" "$tar" "$base" >/dev/null
  rm -f "$tar"
fi

step "3/4 building $image with $engine"
previous=$("$engine" image inspect "$image" --format '{{.Id}}' 2>/dev/null || true)
"$engine" build --quiet --build-arg "BASE_IMAGE=$base" -t "$image" -f "$build/image/Containerfile" "$build/image" >/dev/null
# The image this one replaces, now untagged: removed, so that every `make image` does not keep
# one more (a container still using it keeps it).
current=$("$engine" image inspect "$image" --format '{{.Id}}')
if [ -n "$previous" ] && [ "$previous" != "$current" ]; then
  "$engine" rmi "$previous" >/dev/null 2>&1 || true
fi

step "4/4 checking the executables inside $image"
"$engine" run --rm --network none --entrypoint /bin/sh "$image" -c '
  status=0
  for f in /usr/local/bin/concert /usr/local/bin/concert_*; do
    if ldd "$f" | grep -q "not found"; then
      echo "image: $f: missing libraries:"; ldd "$f" | grep "not found"; status=1
    elif ! "$f" --help >/dev/null 2>&1; then
      echo "image: $f --help failed:"; "$f" --help 2>&1 | tail -3; status=1
    fi
  done
  node --version >/dev/null || { echo "image: node is missing"; status=1; }
  exit $status'

size=$("$engine" image inspect "$image" --format '{{.Size}}')
step "done: $image, $(( size / 1000000 )) MB"
