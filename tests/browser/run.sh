#!/usr/bin/env bash
# The report's interactive page in headless Chromium (CI step): installs Debian's chromium when
# missing, the pinned npm packages (package-lock.json), checks that report/vendor/three is the
# pinned three.js, then runs check.mjs on report/index.html.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
if ! command -v chromium >/dev/null; then
  if [ "$(id -u)" = 0 ]; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q chromium >/dev/null || { apt-get update -q >/dev/null && DEBIAN_FRONTEND=noninteractive apt-get install -y -q chromium >/dev/null; }
  else
    sudo DEBIAN_FRONTEND=noninteractive apt-get install -y -q chromium >/dev/null
  fi
fi
(cd "$here" && npm ci --no-audit --no-fund --silent)
bash "$here/vendor.sh" --check
node "$here/check.mjs" "$here/../../report" "$(command -v chromium)"
