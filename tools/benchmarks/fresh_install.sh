#!/usr/bin/env bash
# The README's main command on a fresh clone with empty caches: `pip install .`, then
# the first `scanlines demo`; prints both times, the load average and the size of the
# installed environment.
#
#     bash tools/benchmarks/fresh_install.sh [COMMIT]   # default: HEAD of this checkout
#
# "Empty caches": XDG_CACHE_HOME (pip's, matplotlib's) and MPLCONFIGDIR point at new
# folders, so pip downloads every dependency again.
set -euo pipefail
repo="$(cd "$(dirname "$0")/../.." && pwd)"
commit="${1:-HEAD}"
work="$(mktemp -d /tmp/scanlines-fresh.XXXXXX)"
trap 'rm -rf "$work"' EXIT
git clone -q "$repo" "$work/clone"
git -C "$work/clone" checkout -q "$commit"
export XDG_CACHE_HOME="$work/cache" MPLCONFIGDIR="$work/mpl"
cd "$work/clone"
echo "commit $(git rev-parse --short HEAD); load before: $(cut -d' ' -f1-3 /proc/loadavg)"
python3 -m venv .venv
# shellcheck disable=SC1091
. .venv/bin/activate
python -m pip install --quiet --upgrade pip >/dev/null 2>&1
start=$(date +%s.%N)
pip install --quiet . >/dev/null 2>&1
installed=$(date +%s.%N)
scanlines demo >/dev/null 2>&1
demo=$(date +%s.%N)
echo "pip install .: $(echo "$installed - $start" | bc) s"
echo "first scanlines demo: $(echo "$demo - $installed" | bc) s"
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "environment: $(du -sm .venv | cut -f1) MB"
