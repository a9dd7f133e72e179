#!/usr/bin/env bash
# Validate every glTF scene with the Khronos glTF validator (npm package gltf-validator).
#
#   scripts/validate_scenes.sh [FILE_OR_DIR ...]      (default: <repo>/scenes)
#
# Installs gltf-validator into scripts/node_modules (git-ignored) when it is missing.
# Exit status: 0 = no errors (warnings/infos are listed but allowed), 1 = at least one error,
# 77 = skipped (node/npm unavailable or the package cannot be installed, e.g. offline).
set -euo pipefail

VALIDATOR_VERSION="2.0.0-dev.3.10"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(dirname "$here")"
pkg="$here/node_modules/gltf-validator"

if ! command -v node >/dev/null 2>&1; then
    echo "SKIP: node is not installed; cannot run the glTF validator" >&2
    exit 77
fi
if [ ! -f "$pkg/package.json" ]; then
    if ! command -v npm >/dev/null 2>&1; then
        echo "SKIP: npm is not installed and $pkg is missing" >&2
        exit 77
    fi
    echo "installing gltf-validator@$VALIDATOR_VERSION into $here/node_modules ..." >&2
    to=""
    if command -v timeout >/dev/null 2>&1; then to="timeout 300"; fi
    if ! $to npm install --prefix "$here" --no-save --no-package-lock --no-audit --no-fund \
            --fetch-retries=1 --fetch-timeout=30000 "gltf-validator@$VALIDATOR_VERSION" >&2 \
        || [ ! -f "$pkg/package.json" ]; then
        echo "SKIP: could not install gltf-validator@$VALIDATOR_VERSION (offline?)" >&2
        exit 77
    fi
fi

if [ "$#" -eq 0 ]; then
    set -- "$root/scenes"
fi
files=()
for arg in "$@"; do
    if [ -d "$arg" ]; then
        while IFS= read -r f; do files+=("$f"); done < <(find "$arg" -maxdepth 1 -type f \( -name '*.gltf' -o -name '*.glb' \) | LC_ALL=C sort)
    else
        files+=("$arg")
    fi
done
if [ "${#files[@]}" -eq 0 ]; then
    echo "error: no .gltf/.glb files found in: $*" >&2
    exit 1
fi

GLTF_VALIDATOR="$pkg" node - "${files[@]}" <<'JS'
const fs = require("fs");
const path = require("path");
const validator = require(process.env.GLTF_VALIDATOR);
const files = process.argv.slice(2);
const severities = ["error", "warning", "info", "hint"];

async function validate(file) {
    const data = new Uint8Array(fs.readFileSync(file));
    const report = await validator.validateBytes(data, {
        uri: path.basename(file),
        maxIssues: 0,
        writeTimestamp: false,
        externalResourceFunction: (uri) => new Promise((resolve, reject) => {
            const p = path.resolve(path.dirname(file), decodeURIComponent(uri));
            fs.readFile(p, (err, buf) => err ? reject(err.toString()) : resolve(new Uint8Array(buf)));
        }),
    });
    return report;
}

(async () => {
    let failed = 0;
    console.log(`gltf-validator ${validator.version()}`);
    for (const file of files) {
        let report;
        try {
            report = await validate(file);
        } catch (e) {
            console.log(`FAIL ${file}: validator could not read it: ${e}`);
            failed++;
            continue;
        }
        const iss = report.issues;
        const info = report.info || {};
        const status = iss.numErrors > 0 ? "FAIL" : "ok  ";
        console.log(`${status} ${file}: ${iss.numErrors} errors, ${iss.numWarnings} warnings, ` +
            `${iss.numInfos} infos, ${iss.numHints} hints; ${info.totalTriangleCount ?? "?"} triangles, ` +
            `${info.totalVertexCount ?? "?"} vertices`);
        for (const m of iss.messages) {
            if (m.severity <= 1) {
                console.log(`     ${severities[m.severity]} ${m.code} at ${m.pointer ?? ""}: ${m.message}`);
            }
        }
        if (iss.numErrors > 0) failed++;
    }
    console.log(failed ? `${failed} of ${files.length} files have errors` : `all ${files.length} files valid`);
    process.exit(failed ? 1 : 0);
})();
JS
