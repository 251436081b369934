#!/usr/bin/env bash
# Vendor three.js for the offline preview page (visemeface preview / speak --preview).
#
# Fetches three@THREE_VERSION and esbuild from the npm registry (the only network step of the
# project, run by a maintainer, never at run time), bundles the few classes the preview uses
# (renderer, scene, camera, lights, AnimationMixer, GLTFLoader) into one minified IIFE that sets
# the global `VF3`, and writes it with three.js's MIT licence into the package data:
#   src/visemeface/export/vendor/three-preview.min.js, three-LICENSE.txt
# The page inlines that file, so it opens from file:// with no network and no module loading.
set -euo pipefail
THREE_VERSION=0.187.0
ESBUILD_VERSION=0.28.2
here="$(cd "$(dirname "$0")/.." && pwd)"
out="$here/src/visemeface/export/vendor"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
npm init -y >/dev/null
npm install --silent --no-audit --no-fund "three@$THREE_VERSION" "esbuild@$ESBUILD_VERSION"
license="$(node -p "JSON.parse(require('fs').readFileSync('node_modules/three/package.json')).license")"
[ "$license" = "MIT" ] || { echo "three.js licence is $license, not MIT" >&2; exit 1; }
cat > entry.js <<'JS'
export { WebGLRenderer, Scene, PerspectiveCamera, HemisphereLight, DirectionalLight, AnimationMixer,
         Box3, Vector3, Color, SRGBColorSpace, LoopOnce } from 'three';
export { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
JS
npx esbuild entry.js --bundle --minify --format=iife --global-name=VF3 --legal-comments=none \
    --target=es2020 --outfile=bundle.js
mkdir -p "$out"
{ echo "/* three.js r${THREE_VERSION#0.} (MIT licence, see three-LICENSE.txt), bundled for visemeface's preview by scripts/vendor_three.sh */"
  cat bundle.js; } > "$out/three-preview.min.js"
cp node_modules/three/LICENSE "$out/three-LICENSE.txt"
if grep -qi '</script' "$out/three-preview.min.js"; then echo "bundle contains </script" >&2; exit 1; fi
ls -l "$out"
