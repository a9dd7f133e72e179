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
        echo "install.sh: chromium is missing and apt-get cannot be used here" >&2
        exit 1
    fi
    export DEBIAN_FRONTEND=noninteractive
    # Fail fast without network rather than retrying for minutes.
    apt_opts=(-o Acquire::Retries=0 -o Acquire::http::Timeout=20 -o Acquire::https::Timeout=20)
    apt-get "${apt_opts[@]}" update -qq >&2
    apt-get "${apt_opts[@]}" install -y -qq --no-install-recommends chromium >&2
fi

if ! command -v node >/dev/null 2>&1; then
    echo "install.sh: node is missing (Debian package nodejs)" >&2
    exit 1
fi
if [ ! -f node_modules/playwright-core/package.json ]; then
    if ! command -v npm >/dev/null 2>&1; then
        echo "install.sh: npm is missing, cannot install playwright-core" >&2
        exit 1
    fi
    # Never download Playwright's own browser builds: the test uses /usr/bin/chromium.
    PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm install --no-save --no-package-lock --no-audit \
        --no-fund --fetch-retries=1 --fetch-timeout=30000 --prefix . playwright-core@1.65.1 >&2
fi

command -v chromium
