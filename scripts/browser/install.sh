#!/usr/bin/env bash
# Installs what the report's browser test needs: Debian's Chromium (/usr/bin/chromium) and
# playwright-core from npm (into scripts/browser/node_modules, its own prefix so that other
# scripts' npm installs do not prune it; no browser download of its own).
# Idempotent and quiet when everything is already there; exits non-zero when something cannot
# be installed (no network, not root), so the caller can skip with a message.
set -euo pipefail
cd "$(dirname "$0")"

if ! command -v chromium >/dev/null 2>&1; then
    if [ "$(id -u)" -ne 0 ] || ! command -v apt-get >/dev/null 2>&1; then
        echo "install_browser: chromium is missing and apt-get cannot be used here" >&2
        exit 1
    fi
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq >&2
    apt-get install -y -qq --no-install-recommends chromium >&2
fi

if [ ! -f node_modules/playwright-core/package.json ]; then
    if ! command -v npm >/dev/null 2>&1; then
        echo "install_browser: npm is missing, cannot install playwright-core" >&2
        exit 1
    fi
    # Never download Playwright's own browser builds: the test uses /usr/bin/chromium.
    PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm install --no-save --no-audit --no-fund \
        --prefix . playwright-core@1 >&2
fi

command -v chromium
