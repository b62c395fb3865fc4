#!/usr/bin/env bash
# Rebuilds three.min.js from npm (needed only to change the three.js version or
# the parts exported in three-entry.js; the build itself never runs npm).
set -euo pipefail
cd "$(dirname "$0")"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
cp three-entry.js "$tmp/"
(cd "$tmp" && npm init -y >/dev/null && npm install --no-audit --no-fund three@0.187.0 esbuild@0.28.2 >/dev/null)
"$tmp/node_modules/.bin/esbuild" "$tmp/three-entry.js" --bundle --minify --format=iife \
  --global-name=THREE --legal-comments=eof --outfile=three.min.js
cp "$tmp/node_modules/three/LICENSE" LICENSE-three.txt
