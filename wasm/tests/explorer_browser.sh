#!/usr/bin/env bash
# The stability explorer driven from outside, as a user would (issue 34):
# Selenium 4 with the distribution's Chromium and chromedriver (no browser
# or driver is downloaded: the test gives Selenium both paths). See
# explorer_browser.py for the steps.
#
#   bash wasm/tests/explorer_browser.sh
#
# Installs what is missing:
#   - Chromium and its driver, the Debian packages `chromium` and
#     `chromium-driver` (apt-get, as root; else set CHROMIUM and CHROMEDRIVER);
#   - Selenium, from pip into a virtual environment: the one of PYTHON
#     (e.g. PYTHON=/work/venv/bin/python) or a fresh one in a temporary folder.
# Needs the built module (bash wasm/build.sh) and the command line
# (target/release/bikedyn, or BIKEDYN=/path/to/bikedyn): neither is built here.
# Screenshots and the downloaded CSV go to wasm/tests/artifacts/ (or ARTIFACTS).
set -euo pipefail
tests="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$tests/../.." && pwd)"

say() { echo "explorer browser test: $*" >&2; }

# Chromium and chromedriver from the distribution's packages.
chromium="${CHROMIUM:-/usr/bin/chromium}"
chromedriver="${CHROMEDRIVER:-/usr/bin/chromedriver}"
if [ ! -x "$chromium" ] || [ ! -x "$chromedriver" ]; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    say "installing chromium and chromium-driver (apt-get)"
    if ! DEBIAN_FRONTEND=noninteractive apt-get install -y -q chromium chromium-driver >&2; then
      apt-get update -q >&2
      DEBIAN_FRONTEND=noninteractive apt-get install -y -q chromium chromium-driver >&2
    fi
  fi
fi
for f in "$chromium" "$chromedriver"; do
  if [ ! -x "$f" ]; then
    say "$f is missing: install the packages (apt-get install -y chromium chromium-driver, as root) or set CHROMIUM and CHROMEDRIVER"
    exit 2
  fi
done

# Python with Selenium 4.
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
python="${PYTHON:-}"
if [ -z "$python" ]; then
  say "creating a virtual environment in $work/venv"
  python3 -m venv "$work/venv"
  python="$work/venv/bin/python"
fi
if ! "$python" -c 'import selenium, sys; sys.exit(0 if int(selenium.__version__.split(".")[0]) >= 4 else 1)' 2>/dev/null; then
  say "installing selenium 4 into $("$python" -c 'import sys; print(sys.prefix)') (pip)"
  "$python" -m pip install -q --disable-pip-version-check 'selenium>=4.11,<5' >&2
fi

export CHROMIUM="$chromium" CHROMEDRIVER="$chromedriver"
export BIKEDYN="${BIKEDYN:-$root/target/release/bikedyn}"
export ARTIFACTS="${ARTIFACTS:-$tests/artifacts}"
# Selenium Manager stays offline (the paths above are given; this is a safeguard).
export SE_OFFLINE=true
status=0
"$python" "$tests/explorer_browser.py" || status=$?
exit $status
