#!/usr/bin/env bash
# Installs those of the given Debian packages that are not installed yet,
# with sudo when not root; packages already present are left alone.
#
#   scripts/apt-install.sh NAME PACKAGE...
#
# NAME (the caller's) starts each line it prints. Shared by install-deps.sh
# and the anchors' build scripts in profiling/anchors/.
set -euo pipefail
if [ $# -lt 2 ]; then
  echo "usage: $0 NAME PACKAGE..." >&2
  exit 2
fi
name=$1
shift
missing=()
for p in "$@"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "$name: all $# packages present"
  exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "$name: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "$name: done"
